"""``python -m experiments sweep`` end to end: 2 host devices in a subprocess vs 1 device in-process,
resume through the CLI, and the CLI's refusals (exit code 2, nothing written)."""

import csv
import json
import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

import jaxsim.montecarlo as mc
from experiments.cli import main
from experiments.noisy_pid_mc import STUDY
from tests.conftest import ROOT, child_env

ARGS = ["sweep", "noisy_pid_mc", "--quick", "--param", "kp=0.4:1.2:3", "--runs", "1500", "--chunk", "1000"]


@pytest.fixture(scope="module")
def two_device_sweep(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "sweep"
    env = child_env()
    env["XLA_FLAGS"] = " ".join(f for f in env.get("XLA_FLAGS", "").split() if "device_count" not in f)
    proc = subprocess.run(
        [sys.executable, "-m", "experiments", *ARGS, "--devices", "2", "--keep-runs", "3", "--out", str(out)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=env,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    assert "run/s" in proc.stderr  # the progress bar reports throughput
    return out


@pytest.fixture(scope="module")
def one_device_rows():
    cfg = STUDY.default_config(quick=True)
    spec = STUDY.per_run(cfg)
    result = mc.sweep(
        spec.metric,
        {**spec.nominal, **spec.uncertain},
        mc.grid({"kp": (0.4, 1.2, 3)}),
        1500,
        0,
        chunk_size=1000,
        devices=1,
    )
    return json.loads(json.dumps(result.table()))


def test_two_devices_through_the_cli_equal_one_device_in_process(two_device_sweep, one_device_rows):
    res = json.loads((two_device_sweep / "results.json").read_text())
    assert res["metrics"]["devices"] == 2 and res["metrics"]["n_points"] == 3
    assert res["metrics"]["chunks_computed"] == 6 and res["metrics"]["runs_per_s"] > 0
    assert res["tables"]["sweep"] == one_device_rows  # bitwise, through JSON's exact float round trip
    for name in ("sweep.csv", "sweep_itae.png", "sweep_overshoot_exceeded.png", "raw_runs.csv", "manifest.json"):
        assert (two_device_sweep / name).exists(), name
    with open(two_device_sweep / "sweep.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["kp"]) for r in rows] == [0.4, 0.8, 1.2]
    for r in rows:  # the event's Wilson interval, recomputed by SciPy from the counts in the table
        k, n = int(float(r["overshoot_exceeded:count"])), int(r["runs"])
        ci = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
        assert float(r["overshoot_exceeded:wilson_low"]) == pytest.approx(ci.low, abs=1e-12)
        assert float(r["overshoot_exceeded:wilson_high"]) == pytest.approx(ci.high, abs=1e-12)
    with open(two_device_sweep / "raw_runs.csv") as fh:
        raw = list(csv.DictReader(fh))
    assert len(raw) == 9 and {r["run"] for r in raw} == {"0", "1", "2"}


def test_resume_through_the_cli_on_one_device_reuses_every_chunk(two_device_sweep, one_device_rows, capsys):
    assert main([*ARGS, "--out", str(two_device_sweep), "--resume"]) == 0
    res = json.loads((two_device_sweep / "results.json").read_text())
    assert res["metrics"]["chunks_loaded"] == 6 and res["metrics"]["chunks_computed"] == 0
    assert res["tables"]["sweep"] == one_device_rows


@pytest.mark.parametrize(
    "extra, match",
    [
        (["--param", "kp=1.2:0.4:3"], "kp: range has lo=1.2 > hi=0.4"),
        (["--param", "nope=0:1:2"], "nope: unknown parameter"),
        (["--param", "K=1:2:2"], "K: is drawn from a distribution"),
        (["--param", "kp=0:1"], "a grid needs lo:hi:n"),
        (["--param", "kp=0:1", "--design", "sobol"], "--points: required"),
        (["--runs", "0"], "--runs: must be ≥ 1"),
    ],
)
def test_cli_rejects_bad_sweeps(tmp_path, capsys, extra, match):
    argv = ["sweep", "noisy_pid_mc", "--quick", "--runs", "100", "--out", str(tmp_path / "x"), *extra]
    assert main(argv) == 2
    assert match in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_cli_refuses_a_folder_of_another_sweep_and_a_study_without_per_run(two_device_sweep, capsys):
    before = {p: p.read_bytes() for p in two_device_sweep.rglob("*") if p.is_file()}
    assert (
        main(
            [
                "sweep",
                "noisy_pid_mc",
                "--quick",
                "--param",
                "kp=0.4:1.2:3",
                "--runs",
                "1600",
                "--out",
                str(two_device_sweep),
                "--resume",
            ]
        )
        == 2
    )
    assert "holds a different sweep" in capsys.readouterr().err
    assert {p: p.read_bytes() for p in two_device_sweep.rglob("*") if p.is_file()} == before
    assert main(["sweep", "linear_pid_accuracy", "--runs", "10"]) == 2
    assert "exposes no per-run metric" in capsys.readouterr().err


def test_noisy_pid_per_run_metric_matches_a_direct_simulation():
    from experiments.noisy_pid_mc import deterministic_itae

    cfg = STUDY.default_config(quick=True)
    spec = STUDY.per_run(cfg)
    # maximum stability degree PI for 0.05 s³ + 0.6 s² + (1 + 2 kp) s + 2 ki: triple root at −4
    assert spec.nominal["kp"] == pytest.approx(0.7, rel=1e-12)
    assert spec.nominal["ki"] == pytest.approx(1.6, rel=1e-12)
    res = mc.monte_carlo(spec.metric, {**spec.nominal, "noise_std": 0.0}, 1000, 0)
    ref = deterministic_itae(cfg, spec.nominal)
    assert float(res["itae"].mean) == pytest.approx(ref, rel=1e-12)
    assert float(res["itae"].std) <= 1e-12 * ref
    assert np.isfinite(ref) and ref > 0


@pytest.mark.slow
def test_the_readme_multi_host_commands_on_loopback_match_one_device(tmp_path, one_device_rows):
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = child_env()
    env["XLA_FLAGS"] = " ".join(f for f in env.get("XLA_FLAGS", "").split() if "device_count" not in f)
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "experiments",
                *ARGS,
                "--out",
                str(tmp_path / f"p{i}"),
                "--coordinator",
                f"127.0.0.1:{port}",
                "--num-processes",
                "2",
                "--process-id",
                str(i),
            ],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for i in range(2)
    ]
    try:
        logs = [p.communicate(timeout=600) for p in procs]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    assert [p.returncode for p in procs] == [0, 0], [err[-2000:] for _, err in logs]
    res = json.loads((tmp_path / "p0" / "results.json").read_text())
    assert res["metrics"]["processes"] == 2 and res["metrics"]["devices"] == 2
    assert res["tables"]["sweep"] == one_device_rows
    assert not (tmp_path / "p1").exists()  # only process 0 writes
