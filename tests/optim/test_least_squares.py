"""Levenberg–Marquardt (optim.least_squares) against NIST's certified values, SciPy's MINPACK and the
gradient tuner; the residual form of a Problem against its loss."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize

import jaxsim.core.costs as costs
from jaxsim.problem import Param, ParamSpace, Problem, Scenario
from jaxsim.problem.reparam import LogInterval
from optim import levenberg_marquardt, standard_tuners, tune
from optim.compile_cache import clear_all
from optim.least_squares import _COMPILED
from optim.problems import PIDTuning
from tests.jax_log import jax_messages
from tests.jaxpr_loops import loop_depths

# NIST StRD nonlinear regression, "Misra1a" (lower difficulty): y = b1·(1 − exp(−b2·x))
MISRA_X = np.array([77.6, 114.9, 141.1, 190.8, 239.9, 289.0, 332.8, 378.4, 434.8, 477.3, 536.8, 593.1, 689.1, 760.0])
MISRA_Y = np.array([10.07, 14.73, 17.94, 23.93, 29.61, 35.18, 40.02, 44.82, 50.76, 55.05, 61.01, 66.40, 75.47, 81.78])
MISRA_CERTIFIED = dict(b1=2.3894212918e02, b2=5.5015643181e-04, ssr=1.2455138894e-01)


def misra(b):
    return b[0] * (1.0 - jnp.exp(-b[1] * MISRA_X)) - MISRA_Y


def rosenbrock(p):
    return jnp.stack([10.0 * (p[1] - p[0] ** 2), 1.0 - p[0]])


@pytest.mark.parametrize("start", [(500.0, 1e-4), (250.0, 5e-4)])  # NIST's two starting points
def test_misra1a_certified_values(start):
    res = levenberg_marquardt(misra, jnp.array(start))
    assert res.converged, res.message
    np.testing.assert_allclose(res.params, [MISRA_CERTIFIED["b1"], MISRA_CERTIFIED["b2"]], rtol=1e-8)
    assert res.loss == pytest.approx(MISRA_CERTIFIED["ssr"], rel=1e-9)
    assert res.mode == "lm-forward" and res.n_evals == res.history.sims[-1]


def test_rosenbrock_against_minpack():
    res = levenberg_marquardt(rosenbrock, jnp.array([-1.2, 1.0]))
    ref = scipy.optimize.least_squares(lambda p: np.asarray(rosenbrock(p)), [-1.2, 1.0], method="lm")
    np.testing.assert_allclose(res.params, ref.x, atol=1e-10)
    assert res.loss < 1e-20 and res.converged
    assert np.all(np.diff(res.history.best_loss) <= 0) and res.history.best_loss[0] == pytest.approx(4.4**2 + 2.2**2)


def test_reparametrised_bounds_hold_and_match_scipy_in_the_same_coordinates():
    """A decay rate in a log box: the iterate stays inside; the optimum is SciPy's on u = log-coordinates."""
    t = jnp.linspace(0.0, 2.0, 21)
    data = 3.0 * jnp.exp(-1.7 * t) + 0.01 * jnp.sin(40.0 * t)
    rep = {"a": LogInterval(0.1, 10.0), "k": LogInterval(0.1, 10.0)}

    def res_fn(p):
        return p["a"] * jnp.exp(-p["k"] * t) - data

    out = levenberg_marquardt(res_fn, {"a": 1.0, "k": 0.5}, reparam=rep)
    assert 0.1 < float(out.params["k"]) < 10.0
    ref = scipy.optimize.least_squares(
        lambda p: np.asarray(res_fn({"a": p[0], "k": p[1]})), [1.0, 0.5], bounds=([0.1, 0.1], [10.0, 10.0])
    )
    np.testing.assert_allclose([out.params["a"], out.params["k"]], ref.x, rtol=1e-6)


def test_a_cold_call_compiles_the_solver_and_the_two_transforms_only():
    """The start's transform to log-coordinates is compiled with the others, not run op by op (five
    eager operations, one compilation each: ≈ 0.1 s of a cold call)."""
    t = jnp.linspace(0.0, 2.0, 11)
    rep = {"a": LogInterval(0.1, 10.0), "k": LogInterval(0.1, 10.0)}
    start = {"a": jnp.asarray(1.0), "k": jnp.asarray(0.5)}  # made before: its own transfer is not the solver's

    def res_fn(p):  # a new function: nothing cached for it
        return p["a"] * jnp.exp(-p["k"] * t) - 2.0 * jnp.exp(-1.3 * t)

    with jax_messages() as messages:
        out = levenberg_marquardt(res_fn, start, reparam=rep)
    names = sorted(m.split(" with ")[0].removeprefix("Compiling ") for m in messages if m.startswith("Compiling"))
    assert names == ["jit(<lambda>)", "jit(flat_start)", "jit(levenberg_marquardt_solve)"], names
    np.testing.assert_allclose([out.params["a"], out.params["k"]], [2.0, 1.3], rtol=1e-8)


def test_reverse_mode_when_residuals_are_fewer_than_parameters_gives_the_forward_result():
    def one_residual(p):  # m = 1 < n = 3: a minimum-norm-like valley; both modes take the same steps
        return jnp.atleast_1d(p[0] + 2.0 * p[1] ** 2 + jnp.sin(p[2]) - 1.0)

    rev = levenberg_marquardt(one_residual, jnp.array([0.3, 0.2, 0.1]), max_steps=20)
    fwd = levenberg_marquardt(one_residual, jnp.array([0.3, 0.2, 0.1]), max_steps=20, jac="forward")
    assert rev.mode == "lm-reverse" and fwd.mode == "lm-forward"
    np.testing.assert_allclose(rev.params, fwd.params, rtol=1e-12)
    assert rev.loss < 1e-20


def test_a_second_call_compiles_nothing():
    before = len(_COMPILED)
    first = levenberg_marquardt(rosenbrock, jnp.array([0.0, 0.0]), max_steps=7)
    mid = len(_COMPILED)
    second = levenberg_marquardt(rosenbrock, jnp.array([0.5, 0.5]), max_steps=7)
    assert mid == before + 1 and len(_COMPILED) == mid  # the same executable, another start
    assert first.n_steps <= 7 and second.n_steps <= 7


def test_a_second_call_does_not_trace_the_residuals():
    """A warm call runs compiled programs only: the residuals' Python (the shape probe, the solver's
    trace) runs on the first call alone — it cost ~60 ms per call on the PID race problem."""
    traced = []

    def counted(b):
        traced.append(1)
        return misra(b)

    first = levenberg_marquardt(counted, jnp.array([500.0, 1e-4]), max_steps=3)
    n_first = len(traced)
    second = levenberg_marquardt(counted, jnp.array([250.0, 5e-4]), max_steps=3)
    assert n_first > 0 and len(traced) == n_first
    assert second.loss != first.loss  # another start really ran
    clear_all()  # what the tuning race's cold runs do: every tuner cache emptied
    assert len(_COMPILED) == 0


# ---------------------------------------------------------------- a Problem with a residual form
@pytest.fixture(scope="module")
def pid_problem():
    tuning = PIDTuning(t_final=1.5)
    lo, hi = tuning.box
    space = ParamSpace(gains=Param(lo=lo, hi=hi, init=(lo + hi) / 2))
    objective = costs.combine(ise=costs.ise(), energy=(tuning.rho, costs.control_energy()))
    problem = Problem(
        "pid", space, objective, lambda p, d: Scenario(tuning.closed_loop(p["gains"]), jnp.zeros(2), tuning.timing)
    )
    return tuning, problem


def test_residuals_square_to_the_loss_and_to_pid_tuning_loss(pid_problem):
    tuning, problem = pid_problem
    p = {"gains": jnp.array([3.0, 2.0, 0.2])}
    r = problem.residuals(p)
    assert problem.least_squares and r.shape == (2 * tuning.n_ticks,)
    assert float(r @ r) == pytest.approx(float(problem.loss(p)), rel=1e-12)
    assert float(r @ r) == pytest.approx(float(tuning.loss(p["gains"])), rel=1e-12)


def test_scenario_residuals_average_like_the_loss(pid_problem):
    _, problem = pid_problem
    objective = costs.combine(ise=costs.ise(), energy=(0.5, costs.control_energy()))
    tuning = PIDTuning(t_final=0.5)

    def build(p, d):
        return Scenario(tuning.closed_loop(p["gains"]), jnp.array([d["x0"], 0.0]), tuning.timing)

    many = problem.replace(objective=objective, build=build, scenarios={"x0": jnp.array([0.0, 0.3, -0.2])})
    p = {"gains": jnp.array([2.0, 1.0, 0.1])}
    r = many.residuals(p)
    assert float(r @ r) == pytest.approx(float(many.loss(p)), rel=1e-12)


def test_problem_optimum_matches_minpack_and_lbfgs(pid_problem):
    _, problem = pid_problem
    res = levenberg_marquardt(problem)
    assert res.converged, res.message
    flat = jax.jit(lambda g: problem.residuals({"gains": g}))
    jac = jax.jit(jax.jacfwd(lambda g: problem.residuals({"gains": g})))
    x0 = np.asarray(problem.space.init["gains"])
    ref = scipy.optimize.least_squares(
        lambda g: np.asarray(flat(g)), x0, jac=lambda g: np.asarray(jac(g)), method="trf", xtol=1e-14, ftol=1e-14
    )
    assert res.loss == pytest.approx(2 * ref.cost, rel=1e-9)
    np.testing.assert_allclose(res.params["gains"], ref.x, rtol=1e-5)
    lb = tune(problem, method="lbfgs", steps=100, gtol=1e-9, patience=20)
    assert res.loss <= lb.loss * (1 + 1e-9)
    # L-BFGS, its line-search trials each one evaluation with the gradient, reaches MINPACK's optimum too
    assert lb.loss == pytest.approx(2 * ref.cost, rel=1e-9) and lb.converged, lb.message


def test_standard_tuner_lm_keeps_the_budget(pid_problem):
    _, problem = pid_problem
    (run,) = standard_tuners(problem, 12, ["lm"]).values()
    res = run()
    assert res.n_sims <= 12 and res.n_steps <= 12


def test_refusals_name_the_argument(pid_problem):
    _, problem = pid_problem
    with pytest.raises(ValueError, match="not a sum of squares"):
        problem.replace(objective=costs.combine(itae=costs.itae())).residuals(problem.space.init)
    with pytest.raises(ValueError, match="not a sum of squares"):
        levenberg_marquardt(problem.replace(objective=costs.combine(ise=costs.ise(), iae=costs.iae())))
    with pytest.raises(ValueError, match="has constraints"):
        levenberg_marquardt(problem.replace(constraints=lambda p: p["gains"][0] - 5.0))
    with pytest.raises(ValueError, match="params0: required"):
        levenberg_marquardt(rosenbrock)
    with pytest.raises(ValueError, match="damping"):
        levenberg_marquardt(rosenbrock, jnp.zeros(2), damping=0.0)
    with pytest.raises(ValueError, match="jac"):
        levenberg_marquardt(rosenbrock, jnp.zeros(2), jac="central")
    with pytest.raises(ValueError, match="residuals: must return a non-empty real vector"):
        levenberg_marquardt(lambda p: jnp.sum(p), jnp.zeros(2))
    with pytest.raises(ValueError, match="loss: not finite"):
        levenberg_marquardt(lambda p: jnp.log(p - 1.0), jnp.zeros(2))


def test_objective_residual_squares_to_the_rate():
    tick = costs.Tick(
        t=jnp.asarray(0.3),
        x=jnp.zeros(2),
        y=jnp.array([0.4, -1.0]),
        y_meas=jnp.zeros(2),
        measured=jnp.asarray(True),
        u=jnp.array([2.5]),
        r=jnp.array([1.0, 0.5]),
        d=jnp.zeros(1),
        x_hat=None,
    )
    ts = jnp.asarray(0.01)
    obj = costs.combine(
        ise=costs.ise(),
        energy=(0.3, costs.control_energy(offset=0.5)),
        sat=(2.0, costs.saturation_excess(1.0)),
        pen=costs.penalty(lambda tk: tk.y - 0.2, weight=4.0),
    )
    r = obj.residual(tick, ts)
    assert float(r @ r) == pytest.approx(float(obj.rate(tick, ts)), rel=1e-14)
    assert costs.combine(a=costs.ise(), b=costs.itae()).residual is None
    assert costs.combine(a=(-1.0, costs.ise())).residual is None
    assert costs.penalty(lambda tk: tk.y, weight=-1.0).residual is None  # a reward, not a square


def test_the_pure_kernel_vmaps_like_a_loop():
    """jaxsim.core's kernel under vmap (lanes stop at different steps) equals one run per start."""
    from jaxsim.core.least_squares import levenberg_marquardt_solve

    starts = jnp.array([[-1.2, 1.0], [2.0, 2.0], [0.0, -1.0]])
    solve = jax.jit(lambda u: levenberg_marquardt_solve(rosenbrock, u, max_steps=50))
    batched = jax.vmap(solve)(starts)
    for i, u in enumerate(starts):
        one = solve(u)
        np.testing.assert_allclose(batched.u[i], one.u, rtol=1e-12, atol=1e-14)
        assert int(batched.step[i]) == int(one.step) and int(batched.status[i]) == int(one.status)
    assert len(set(np.asarray(batched.step).tolist())) > 1  # the lanes did stop at different steps


def test_the_kernel_holds_one_copy_of_the_residuals_jacobian():
    """The start is the loop's first evaluation: a residual function with one ``scan`` (a rollout)
    appears once in the solver, inside the loop — a second copy before it doubled the compile."""
    from jaxsim.core.least_squares import levenberg_marquardt_solve

    t = jnp.linspace(0.0, 1.0, 20)

    def rollout_residuals(u):  # a first-order lag simulated by scan, against a target response
        def tick(x, tk):
            x = x + 0.05 * (u[0] * jnp.sin(tk) - u[1] * x)
            return x, x

        return jax.lax.scan(tick, 0.0, t)[1] - 0.3 * t

    for forward, inside_the_loop in ((True, [1]), (False, [1, 1])):  # reverse: the rollout and its adjoint
        jaxpr = jax.make_jaxpr(lambda u: levenberg_marquardt_solve(rollout_residuals, u, max_steps=5, forward=forward))
        assert loop_depths(jaxpr(jnp.array([1.0, 0.5]))) == [0, *inside_the_loop]  # the solver's while, then scans
    out = levenberg_marquardt_solve(rollout_residuals, jnp.array([1.0, 0.5]), max_steps=0)
    assert int(out.status) == 4 and int(out.n_evals) == 1 and int(out.step) == 0
    assert float(out.cost) == pytest.approx(float(jnp.sum(rollout_residuals(jnp.array([1.0, 0.5])) ** 2)), rel=1e-15)
