"""Piezo accelerometer: its mechanical resonance and its low-frequency (charge-leak) roll-off.

Two seed-004 papers on the same sensor family:

* **#25 (Palkov, lines 8122–8225; spec seed004_part2 §2.9)** — the resonance, excited through the
  built-in calibration coil (VKU).  No model is printed; a second-order resonator from coil current
  ``u`` (A) to output voltage ``y`` (V) is implied:
  ``ÿ + (ω_n/Q)·ẏ + ω_n²·y = g·ω_n²·u``.  :class:`ResonatorParams` stores the amplitude-peak
  frequency ``f_r`` (what the paper reports: 807.5 Hz by white noise, 807 Hz by stepped sine), the
  quality factor ``Q`` (**assumed**, not in the paper) and the static gain ``g`` (V/A, **assumed**).
* **#26 (KD45 calibration bench, lines 8226–8335; spec §2.8)** — the voltage-mode piezo high-pass
  ``V(s) = K_p·a(s)·sτ/(1 + sτ)``, ``τ = C_d·(Z_n ∥ R_y)`` (the transfer function is not printed; this is
  the standard charge-leak model, spec [reconstructed]); the bench drives the sensor by rotating it
  in gravity, ``a(t) = g₀·cos φ·sin(2π f t)``.  :class:`BenchParams` holds the paper's KD45 values.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp

from jaxsim.core.pytree import pytree_dataclass
from jaxsim.core.system import Plant
from jaxsim.core.validation import check_finite, check_positive

G0 = 9.80665  # m/s², standard gravity (the bench's excitation scale)


# --- #25: the resonance -------------------------------------------------------------------------


@pytree_dataclass
class ResonatorParams:
    """``f_r`` Hz (amplitude peak; paper #25: 807.5 Hz), ``q`` (assumed 35: the half-power width of
    the paper's Table 1 is ≈ 22 Hz), ``gain`` V/A at DC (assumed 1)."""

    f_r: Any = 807.5
    q: Any = 35.0
    gain: Any = 1.0


def natural_frequency(p: ResonatorParams) -> jax.Array:
    """``f_n = f_r / √(1 − 1/(2Q²))`` (Hz)."""
    return p.f_r / jnp.sqrt(1.0 - 0.5 / p.q**2)


def resonator_state_space(p: ResonatorParams) -> tuple[jax.Array, jax.Array, jax.Array]:
    """``(A (2, 2), B (2, 1), C (1, 2))`` for the state ``[y, ẏ]`` (V, V/s), time in s."""
    wn = 2 * jnp.pi * natural_frequency(p)
    a = jnp.array([[0.0, 1.0], [-(wn**2), -wn / p.q]])
    b = jnp.stack([jnp.zeros_like(wn), p.gain * wn**2])[:, None]
    return a, b, jnp.array([[1.0, 0.0]])


def resonator_response(p: ResonatorParams, f: Any) -> jax.Array:
    """Complex steady-state response ``y/u`` (V/A) at ``f`` Hz."""
    wn, w = 2 * jnp.pi * natural_frequency(p), 2 * jnp.pi * jnp.asarray(f)
    return p.gain * wn**2 / (wn**2 - w**2 + 1j * w * wn / p.q)


def resonator_dynamics(p: ResonatorParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    a, b, _ = resonator_state_space(p)
    return a @ x + b[:, 0] * u[0]


def _first(p: Any, x: jax.Array) -> jax.Array:
    return x[:1]


def resonator(params: ResonatorParams | None = None, **kwargs: Any) -> Plant:
    """The resonance as a :class:`~jaxsim.core.system.Plant` (coil current → output voltage)."""
    p = params if params is not None else ResonatorParams(**kwargs)
    check_positive("f_r", p.f_r)
    check_finite("gain", p.gain)
    check_finite("q", p.q)
    if float(jnp.min(jnp.asarray(p.q))) <= 2**-0.5:
        raise ValueError(f"q: the resonance needs Q > 1/√2, got {p.q!r}")
    return Plant(p, resonator_dynamics, _first, n_states=2, n_inputs=1, n_outputs=1, name="piezo_resonator")


# --- #26: the calibration bench ----------------------------------------------------------------


@pytree_dataclass
class BenchParams:
    """KD45 (paper #26): ``kp`` V/g (10 mV/g), ``c_d`` F (1.2 nF), ``z_n`` Ω load (5.5 MΩ), ``r_y`` Ω
    sensor's own resistance (6·10¹¹ Ω).  Cable capacitance ignored (assumed, spec §2.8)."""

    kp: Any = 10e-3
    c_d: Any = 1.2e-9
    z_n: Any = 5.5e6
    r_y: Any = 6e11


def time_constant(p: BenchParams) -> jax.Array:
    """``τ = C_d·(Z_n ∥ R_y)`` (s)."""
    return p.c_d * p.z_n * p.r_y / (p.z_n + p.r_y)


def corner_frequency(p: BenchParams) -> jax.Array:
    """High-pass corner ``f_c = 1/(2πτ)`` (Hz)."""
    return 1.0 / (2 * jnp.pi * time_constant(p))


def bench_response(p: BenchParams, f: Any) -> jax.Array:
    """Complex ``V/a`` (V per g) at ``f`` Hz: ``K_p·jωτ/(1 + jωτ)``."""
    s = 2j * jnp.pi * jnp.asarray(f) * time_constant(p)
    return p.kp * s / (1.0 + s)


def rotating_input(f: Any, t: Any, phi: Any = 0.0, amplitude: Any = 1.0) -> jax.Array:
    """Bench excitation (paper #26 eqs. 1–2) in g: ``amplitude·cos φ·sin(2π f t)`` — rotating the
    sensor at ``f`` Hz in gravity (``amplitude = 1`` g; φ the axis inclination, rad)."""
    return amplitude * jnp.cos(phi) * jnp.sin(2 * jnp.pi * jnp.asarray(f) * jnp.asarray(t))


def bench_dynamics(p: BenchParams, x: jax.Array, u: jax.Array, t: jax.Array) -> jax.Array:
    """State ``x`` = the leaked part of ``K_p·a`` (V): ``τ ẋ = K_p a − x``; ``u = [a]`` in g."""
    return (p.kp * u[:1] - x) / time_constant(p)


def _bench_output(p: BenchParams, x: jax.Array) -> jax.Array:
    return -x[:1]


def _bench_feedthrough(p: BenchParams, u: jax.Array) -> jax.Array:
    return p.kp * u[:1]


def bench_sensor(params: BenchParams | None = None, **kwargs: Any) -> Plant:
    """The KD45 on the bench as a plant: ``u = [a]`` (g) → ``V = K_p a − x`` (V)."""
    p = params if params is not None else BenchParams(**kwargs)
    for name in ("c_d", "z_n", "r_y"):
        check_positive(name, getattr(p, name))
    check_finite("kp", p.kp)
    return Plant(
        p,
        bench_dynamics,
        _bench_output,
        n_states=1,
        n_inputs=1,
        n_outputs=1,
        name="kd45_bench",
        feedthrough=_bench_feedthrough,
    )
