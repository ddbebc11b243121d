"""The mrr_localisation study through the CLI (tiny preset): files, claims against their paired
intervals, and its localisation table recomputed from the same simulated scenes by ``motmetrics``."""

import jax
import jax.numpy as jnp
import motmetrics
import numpy as np
import pytest

from experiments.mrr_localisation import SENSOR_SETS, STUDY, simulate_fn, visible
from tests.experiments.study_cli import recorded_config, run_quick_study


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("mrr")
    return out, run_quick_study("mrr_localisation", out, preset="tiny")


def test_files_config_and_claims(result):
    out, res = result
    _, cfg = STUDY.resolve("tiny", [])
    assert res["config"] == recorded_config(cfg)
    for name in ("localisation.csv", "paired_differences.csv", "localisation.png", "reproduction.csv"):
        assert (out / name).stat().st_size > 0, name
    verdict = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    diffs = {r["difference"]: r for r in res["tables"]["paired_differences"]}
    lowers = diffs["mean_error_cm"]["ci95_hi"] < 0
    raises = diffs["mota_pct"]["ci95_lo"] > 0
    assert res["metrics"]["rangefinder_lowers_mean_error"] == float(lowers)
    assert (verdict["rangefinder_lowers_mean_error"] == "reproduced") == lowers
    assert (verdict["rangefinder_raises_mota"] == "reproduced") == raises
    for key in ("scene", "sensors", "filter", "mota"):
        assert res["assumptions"][key]["why"]


def test_table_equals_motmetrics_on_the_same_scenes(result):
    """The study's scenes re-simulated (same keys); each run scored by motmetrics; pooled MOTA and the
    mean / max match distance equal the study's table."""
    _, res = result
    _, cfg = STUDY.resolve("tiny", [])
    sim = simulate_fn(cfg)
    keys = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.n_runs)
    rows = {r["sensors"]: r for r in res["tables"]["localisation"]}
    for name, use in SENSOR_SETS.items():
        truth, est, cov, updated, _ = (np.asarray(a) for a in sim(keys, jnp.asarray(use)))
        accs = []
        for r in range(cfg.n_runs):
            acc = motmetrics.MOTAccumulator(auto_id=True)
            ids = np.arange(cfg.n_objects)
            for t in range(truth.shape[1]):
                u = updated[r, t]
                d2 = motmetrics.distances.norm2squared_matrix(truth[r, t], est[r, t, u], max_d2=cfg.match_threshold**2)
                acc.update(ids, ids[u], d2)
            accs.append(acc)
        mh = motmetrics.metrics.create()
        summary = mh.compute_many(accs, metrics=["mota", "num_misses", "num_switches"], generate_overall=True)
        overall = summary.loc["OVERALL"]
        assert rows[name]["mota_pct"] == pytest.approx(100 * overall["mota"], rel=1e-12)
        assert rows[name]["misses"] == overall["num_misses"]
        assert rows[name]["switches"] == overall["num_switches"]
        ev = [a.mot_events[a.mot_events["Type"].isin(["MATCH", "SWITCH"])] for a in accs]  # one per pair
        d = np.concatenate([np.sqrt(e["D"].to_numpy(dtype=float)) for e in ev])
        assert rows[name]["mean_error_cm"] == pytest.approx(100 * d.mean(), rel=1e-10)
        assert rows[name]["max_error_cm"] == pytest.approx(100 * d.max(), rel=1e-10)
        # consistent filters: NEES ~ χ²(2), median 1.39, 95 % inside its 95 % interval
        assert 1.0 < rows[name]["median_position_nees"] < 1.8
        assert 88.0 < rows[name]["position_nees_in_95_pct"] < 99.0


def test_occlusion_geometry():
    """A disc hides exactly the objects whose centres lie within its angular half-width behind it."""
    sensor = jnp.zeros(2)
    pos = jnp.array([[2.0, 0.0], [4.0, 0.0], [4.0, 0.5], [1.0, 1.0], [0.5, 0.5]])
    # object 1 is behind object 0 on the same ray; object 2 is 7.1° off it (half-width of 0: 4.3°);
    # object 3 is behind object 4 on the diagonal
    np.testing.assert_array_equal(visible(pos, sensor, 0.15), [True, False, True, False, True])
