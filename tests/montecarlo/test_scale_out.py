"""Scale-out in separate processes: 2 host devices, two ``jax.distributed`` processes on loopback,
and a sweep killed with SIGKILL then resumed — all bitwise identical to one uninterrupted process."""

import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

import jaxsim.montecarlo as mc
from tests.conftest import ROOT, child_env
from tests.montecarlo import _worker
from tests.montecarlo._demo import SPACE, demo_fn

pytestmark = pytest.mark.slow


def _env(devices=None):
    env = child_env()
    flags = " ".join(f for f in env.get("XLA_FLAGS", "").split() if "device_count" not in f)
    if devices is not None:
        flags += f" --xla_force_host_platform_device_count={devices}"
    env["XLA_FLAGS"] = flags.strip()
    return env


def _worker_cmd(*args):
    return [sys.executable, "-m", "tests.montecarlo._worker", *map(str, args)]


def _assert_equal_to(npz_path, result, devices, processes):
    got = np.load(npz_path)
    assert int(got["__devices__"]) == devices and int(got["__processes__"]) == processes
    expected = result.arrays()
    assert set(got.files) - {"__devices__", "__processes__"} == set(expected)
    for k, v in expected.items():
        assert np.array_equal(got[k], v, equal_nan=True), k


@pytest.fixture(scope="module")
def one_process_result():
    return mc.monte_carlo(demo_fn, SPACE, _worker.N, _worker.KEY, chunk_size=_worker.CHUNK)


def test_two_host_devices_give_bitwise_identical_statistics(tmp_path, one_process_result):
    out = tmp_path / "two_devices.npz"
    proc = subprocess.run(
        _worker_cmd("devices", out), env=_env(2), cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr
    _assert_equal_to(out, one_process_result, devices=2, processes=1)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_two_distributed_processes_on_loopback_match_one_process(tmp_path, one_process_result):
    port = _free_port()
    outs = [tmp_path / f"process{i}.npz" for i in range(2)]
    procs = [
        subprocess.Popen(
            _worker_cmd("distributed", i, port, outs[i], tmp_path / "ckpt"),
            env=_env(1),
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for i in range(2)
    ]
    try:
        logs = [p.communicate(timeout=300) for p in procs]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    for p, (_, err) in zip(procs, logs):
        assert p.returncode == 0, err
    for out in outs:  # every process returns the same statistics as a single process
        _assert_equal_to(out, one_process_result, devices=2, processes=2)
    assert len(list((tmp_path / "ckpt" / "chunks").glob("*.chunk"))) == 4  # process 0 checkpoints


def test_sweep_killed_with_sigkill_resumes_to_the_uninterrupted_result(tmp_path):
    out = tmp_path / "sweep"
    proc = subprocess.Popen(
        _worker_cmd("sweep", out, 0.5),
        env=_env(1),
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 240
        while len(list(out.glob("chunks/*.chunk"))) < 3:
            assert proc.poll() is None, proc.stderr.read()
            assert time.monotonic() < deadline, "the sweep wrote no chunks in time"
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == -signal.SIGKILL
    design = mc.grid({"fixed": (1.0, 3.0, 2)})
    total = 2 * (_worker.SWEEP_N // _worker.SWEEP_CHUNK)
    written = len(list(out.glob("chunks/*.chunk")))
    assert 3 <= written < total

    resumed = mc.sweep(
        demo_fn, SPACE, design, _worker.SWEEP_N, _worker.KEY, chunk_size=_worker.SWEEP_CHUNK, out=out, resume=True
    )
    assert resumed.chunks_loaded == written and resumed.chunks_computed == total - written
    assert not resumed.rejected_chunks
    uninterrupted = mc.sweep(demo_fn, SPACE, design, _worker.SWEEP_N, _worker.KEY, chunk_size=4_000)
    for a, b in zip(resumed.points, uninterrupted.points):
        aa, bb = a.arrays(), b.arrays()
        assert all(np.array_equal(aa[k], bb[k], equal_nan=True) for k in aa)
