"""Output folders of ``python -m experiments run`` and ``sweep``: a user's files are never overwritten,
a previous output of the same study is replaced whole (no stale files), an unwritable folder is
refused before anything is computed, a failed run leaves the previous output intact — each refusal
one ``error:`` line and exit code 2.  A tiny fake study stands in for the real ones."""

import builtins
import errno
import io
import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import jax
import pytest

from experiments import cli, output_folder, registry
from experiments.output_folder import MARKER
from experiments.runner import PerRun, Study, StudyResult


@dataclass(frozen=True)
class Config:
    answer: float = 42.0
    tables: int = 2  # how many tables the run writes (fewer on a later run: stale files must go)
    fail: bool = False  # raise inside the study, after "computing"


def _metric(key, p):
    return {"y": p["a"] + jax.random.normal(key)}


@pytest.fixture
def fake(monkeypatch):
    """Two fake studies in the registry; ``fake.calls`` lists the configs their ``run`` was given."""
    calls = []

    def run(cfg, progress):
        calls.append(cfg)
        if cfg.fail:
            raise RuntimeError("the study crashed half-way")
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(1, 1))
        tables = {f"table{i}": [{"i": i, "value": cfg.answer}] for i in range(cfg.tables)}
        return StudyResult(metrics={"answer": cfg.answer}, tables=tables, figures={"plot": fig})

    studies = {
        name: Study(name, "a fake study", Config, run, per_run=lambda cfg: PerRun(_metric, {"a": 1.0}))
        for name in ("fake", "other_fake")
    }
    original = registry.get_study

    def get_study(name):
        return studies[name] if name in studies else original(name)

    monkeypatch.setattr(registry, "get_study", get_study)
    monkeypatch.setattr(cli, "get_study", get_study)
    run.calls = calls
    return run


def _snapshot(folder):
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _one_error_line(capsys):
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert "Traceback" not in err and lines[-1].startswith("error: "), err
    return lines[-1]


@pytest.fixture
def read_only(monkeypatch):
    """``read_only(folder)``: no new file can be made in ``folder``.  As a normal user: ``chmod 555``.
    As root, who ignores permission bits (these tests run as root here), the calls that create
    files or folders in it fail with ``EACCES`` as they would on a read-only folder."""
    chmodded = []

    def make(folder):
        folder = Path(folder).absolute()
        if os.geteuid() != 0:
            folder.chmod(0o555)
            chmodded.append(folder)
        else:

            def inside(path):
                try:
                    return Path(os.fsdecode(path)).absolute().is_relative_to(folder)
                except TypeError:  # a file descriptor
                    return False

            def refuse(path):
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), os.fsdecode(path))

            real_os_open, real_open, real_mkdir = os.open, builtins.open, os.mkdir

            def os_open(path, flags, *args, **kwargs):
                if inside(path) and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT):
                    refuse(path)
                return real_os_open(path, flags, *args, **kwargs)

            def py_open(path, mode="r", *args, **kwargs):
                if inside(path) and set(mode) & set("wax+"):
                    refuse(path)
                return real_open(path, mode, *args, **kwargs)

            def mkdir(path, *args, **kwargs):
                if inside(path):
                    refuse(path)
                return real_mkdir(path, *args, **kwargs)

            monkeypatch.setattr(os, "open", os_open)
            monkeypatch.setattr(builtins, "open", py_open)
            monkeypatch.setattr(io, "open", py_open)
            monkeypatch.setattr(os, "mkdir", mkdir)
        with pytest.raises(PermissionError):  # the folder really refuses a new file now
            tempfile.mkstemp(dir=folder)

    yield make
    for folder in chmodded:
        folder.chmod(0o755)


# -- run -----------------------------------------------------------------------------------------


def test_run_refuses_a_folder_with_a_users_files_and_leaves_them_untouched(tmp_path, fake, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "results.json").write_text('{"my": "thesis results"}')
    (out / "designs.csv").write_text("a,b\n1,2\n")
    before = _snapshot(out)
    assert cli.main(["run", "fake", "--out", str(out)]) == 2
    line = _one_error_line(capsys)
    assert str(out) in line and "designs.csv, results.json" in line
    assert _snapshot(out) == before and fake.calls == []


def test_run_refuses_another_studys_output_and_a_sweep_folder(tmp_path, fake, capsys):
    out = tmp_path / "out"
    assert cli.main(["run", "other_fake", "--out", str(out)]) == 0
    capsys.readouterr()
    before = _snapshot(out)
    assert cli.main(["run", "fake", "--out", str(out)]) == 2
    assert "holds the output of `run other_fake`, not of `run fake`" in _one_error_line(capsys)
    assert cli.main(["sweep", "other_fake", "--runs", "10", "--out", str(out)]) == 2
    assert "holds the output of `run other_fake`, not of `sweep other_fake`" in _one_error_line(capsys)
    assert _snapshot(out) == before and len(fake.calls) == 1


@pytest.mark.parametrize("exchange", [True, False], ids=["renameat2", "two-renames"])
def test_run_replaces_its_own_previous_output_and_leaves_no_stale_file(tmp_path, fake, capsys, monkeypatch, exchange):
    if not exchange:
        monkeypatch.setattr(output_folder, "_exchange", lambda a, b: False)
    out = tmp_path / "out"
    assert cli.main(["run", "fake", "--out", str(out), "--set", "tables=2"]) == 0
    assert set(_snapshot(out)) == {MARKER, "results.json", "table0.csv", "table1.csv", "plot.png"}
    assert cli.main(["run", "fake", "--out", str(out), "--set", "tables=1", "--set", "answer=7"]) == 0
    assert set(_snapshot(out)) == {MARKER, "results.json", "table0.csv", "plot.png"}  # table1.csv gone
    assert json.loads((out / "results.json").read_text())["metrics"] == {"answer": 7.0}
    marker = json.loads((out / MARKER).read_text())
    assert (marker["command"], marker["study"]) == ("run", "fake")
    assert marker["files"] == ["plot.png", "results.json", "table0.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging folder left beside it


def test_run_replaces_an_output_written_before_markers_existed(tmp_path, fake, capsys):
    """A folder from an older version (no marker; results.json naming the study, CSV/PNG files)
    is this study's previous output: re-running the README command over it works."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "results.json").write_text(json.dumps({"study": "fake", "metrics": {}}))
    (out / "old_table.csv").write_text("a\n1\n")
    (out / "old_plot.png").write_bytes(b"png")
    assert cli.main(["run", "fake", "--out", str(out)]) == 0
    assert "old_table.csv" not in _snapshot(out) and MARKER in _snapshot(out)
    (out / MARKER).unlink()  # the same folder, older, but with a user's note in it: refused
    (out / "notes.txt").write_text("mine")
    assert cli.main(["run", "fake", "--out", str(out)]) == 2
    assert "notes.txt" in _one_error_line(capsys)


def test_an_interrupted_run_leaves_the_previous_output_intact(tmp_path, fake, capsys, monkeypatch):
    out = tmp_path / "out"
    assert cli.main(["run", "fake", "--out", str(out)]) == 0
    before = _snapshot(out)
    with pytest.raises(RuntimeError, match="crashed half-way"):
        cli.main(["run", "fake", "--out", str(out), "--set", "fail=true", "--set", "answer=1"])
    assert _snapshot(out) == before

    def disk_full(*_):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(out / "table0.csv"))

    monkeypatch.setattr(cli, "write_report", disk_full)
    capsys.readouterr()
    assert cli.main(["run", "fake", "--out", str(out), "--set", "answer=1"]) == 2
    assert "No space left on device" in _one_error_line(capsys)
    assert _snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


@pytest.mark.parametrize("where", ["read-only folder", "under a regular file"])
def test_run_into_an_unwritable_place_is_refused_before_computing(tmp_path, fake, capsys, read_only, where):
    if where == "read-only folder":
        out = tmp_path / "ro"
        out.mkdir()
        read_only(out)
    else:  # a real failure even for root: the folder's parent is a file
        (tmp_path / "blocker").write_text("a file")
        out = tmp_path / "blocker" / "out"
    assert cli.main(["run", "fake", "--out", str(out)]) == 2
    line = _one_error_line(capsys)
    assert "cannot" in line and ("blocker" in line if where != "read-only folder" else str(out) in line)
    assert fake.calls == []  # refused before the study ran
    assert sorted(p.name for p in tmp_path.iterdir()) == ["blocker" if where != "read-only folder" else "ro"]


# -- sweep ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("where", ["read-only folder", "under a regular file"])
def test_sweep_into_an_unwritable_place_exits_2_with_one_error_line(tmp_path, fake, capsys, read_only, where):
    if where == "read-only folder":
        out = tmp_path / "ro"
        out.mkdir()
        read_only(out)
    else:
        (tmp_path / "blocker").write_text("a file")
        out = tmp_path / "blocker" / "out"
    assert cli.main(["sweep", "fake", "--runs", "10", "--out", str(out)]) == 2
    assert "cannot" in _one_error_line(capsys)


def test_sweep_refuses_a_users_files_and_keeps_its_own_folder_tidy_across_resumes(tmp_path, fake, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "sweep.csv").write_text("my,own\n")
    assert cli.main(["sweep", "fake", "--runs", "10", "--out", str(mine)]) == 2
    assert "holds files that are not a previous output of `sweep fake`: sweep.csv" in _one_error_line(capsys)
    assert _snapshot(mine) == {"sweep.csv": b"my,own\n"}

    out = tmp_path / "sweep"
    args = ["sweep", "fake", "--runs", "10", "--param", "a=0:1:2", "--out", str(out)]
    assert cli.main([*args, "--keep-runs", "2"]) == 0
    report = {MARKER, "results.json", "sweep.csv", "raw_runs.csv", "sweep_y.png"}
    assert set(_snapshot(out)) == report | {
        "manifest.json",
        "chunks/p00000_c000000.chunk",
        "chunks/p00001_c000000.chunk",
    }
    assert cli.main([*args, "--resume"]) == 0  # resumed without --keep-runs: raw_runs.csv is stale now
    assert set(_snapshot(out)) == (report - {"raw_runs.csv"}) | {
        "manifest.json",
        "chunks/p00000_c000000.chunk",
        "chunks/p00001_c000000.chunk",
    }
    marker = json.loads((out / MARKER).read_text())
    assert (marker["command"], marker["study"]) == ("sweep", "fake")
    assert marker["files"] == ["results.json", "sweep.csv", "sweep_y.png"]

    for name in report - {"raw_runs.csv"}:  # as if killed before the report: only the checkpoint is left
        (out / name).unlink()
    (out / ".sweep.csv.tmp-4242").write_text("half")  # and the leftovers of a kill while writing
    (out / ".jaxsim-probe-x1y2").write_text("")
    capsys.readouterr()
    assert cli.main([*args, "--resume"]) == 0
    assert not list(out.glob(".*"))
    res = json.loads((out / "results.json").read_text())
    assert res["metrics"]["chunks_loaded"] == 2 and res["metrics"]["chunks_computed"] == 0
    (out / "notes.txt").write_text("a user's note")
    assert cli.main([*args, "--resume"]) == 2
    assert "notes.txt" in _one_error_line(capsys)
    assert (out / "notes.txt").read_text() == "a user's note"


def test_sweep_resume_after_the_studys_metric_was_edited_is_refused(tmp_path, fake, capsys, monkeypatch):
    out = tmp_path / "sweep"
    args = ["sweep", "fake", "--runs", "10", "--out", str(out)]
    assert cli.main(args) == 0
    before = _snapshot(out)

    def _metric(key, p):  # the same function, body edited
        return {"y": p["a"] + 0.5 * jax.random.normal(key)}

    edited = Study("fake", "a fake study", Config, fake, per_run=lambda cfg: PerRun(_metric, {"a": 1.0}))
    monkeypatch.setattr(registry, "get_study", lambda name: edited)
    capsys.readouterr()
    assert cli.main([*args, "--resume"]) == 2
    line = _one_error_line(capsys)
    assert f"the per-run computation changed since the chunks in {out} were written (computation hash" in line
    assert _snapshot(out) == before
