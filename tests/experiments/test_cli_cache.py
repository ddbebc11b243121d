"""The CLI's persistent compilation cache: which folder, and that compiled programs land there."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from experiments.cli import cache_dir
from tests.conftest import ROOT


def _env(monkeypatch, **values):
    for name in ("JAXSIM_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR", "XDG_CACHE_HOME"):
        monkeypatch.delenv(name, raising=False)
    for name, value in values.items():
        monkeypatch.setenv(name, value)


def test_cache_dir_precedence(monkeypatch, tmp_path):
    _env(monkeypatch, XDG_CACHE_HOME=str(tmp_path))
    assert cache_dir() == tmp_path / "jaxsim" / "jax"  # the default
    _env(monkeypatch, JAX_COMPILATION_CACHE_DIR=str(tmp_path / "tests"))
    assert cache_dir() is None  # the caller's JAX setting is left alone (tests spawn the CLI with theirs)
    _env(monkeypatch, JAXSIM_CACHE_DIR=str(tmp_path / "mine"), JAX_COMPILATION_CACHE_DIR=str(tmp_path / "x"))
    assert cache_dir() == tmp_path / "mine"
    _env(monkeypatch, JAXSIM_CACHE_DIR="")
    assert cache_dir() is None  # off


SCRIPT = """
from experiments.cli import enable_compilation_cache
enable_compilation_cache()
import jax
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0)
print(float(jax.jit(lambda x: x * 3.0 + 1.0)(2.0)))
"""


def _run(env: dict[str, str]) -> None:
    base = {k: v for k, v in os.environ.items() if k not in ("JAXSIM_CACHE_DIR", "JAX_COMPILATION_CACHE_DIR")}
    proc = subprocess.run(
        [sys.executable, "-c", SCRIPT],
        cwd=ROOT,
        env={**base, "PYTHONPATH": str(ROOT), **env},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0 and proc.stdout.strip() == "7.0", proc.stderr[-2000:]


def test_cli_cache_writes_to_jaxsim_cache_dir_or_the_callers_jax_dir(tmp_path):
    ours, theirs = tmp_path / "jaxsim", tmp_path / "jax"
    _run({"JAXSIM_CACHE_DIR": str(ours)})
    assert any(Path(ours).iterdir())
    _run({"JAX_COMPILATION_CACHE_DIR": str(theirs)})
    assert any(Path(theirs).iterdir())
    off = tmp_path / "off"
    _run({"JAXSIM_CACHE_DIR": "", "JAX_COMPILATION_CACHE_DIR": str(off)})
    assert not off.exists() or not any(off.iterdir())


def test_the_cli_run_in_process_follows_the_suites_cache_setting():
    """``experiments.cli.main`` called inside a test worker must not switch on the user's cache folder
    (a worker that did wrote every later compilation to ~/.cache/jaxsim, and one such write crashed)."""
    import jax

    from experiments.cli import enable_compilation_cache
    from tests.conftest import CACHE_DIR

    enable_compilation_cache()
    if CACHE_DIR is None:
        assert not jax.config.jax_enable_compilation_cache
    else:
        assert jax.config.jax_compilation_cache_dir == str(CACHE_DIR)
