"""The study runner: claims and their verdicts, config resolution (preset, then --set) recorded as run,
the lazy registry (a broken study breaks only itself), and the static HTML report (every image and
link resolves).  Tiny fake studies stand in for the real ones."""

import csv
import json
import sys
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path

import pytest

import experiments
from experiments import cli, registry
from experiments.runner import PAPERS, Claim, Study, StudyResult, as_study, assumption, check_claims, paper_facts


@dataclass(frozen=True)
class Config:
    gain: float = 2.0
    steps: int = 100
    label: str = "a<b>"


def _run(cfg, progress):
    import matplotlib.pyplot as plt

    _run.calls.append(cfg)
    fig, ax = plt.subplots(figsize=(2, 2))
    ax.plot([0, 1], [0, cfg.gain])
    return StudyResult(
        metrics={"gain2": cfg.gain**2, "steps": float(cfg.steps)},
        tables={"values": [{"gain": cfg.gain}]},
        figures={"line": fig},
    )


_run.calls = []

CLAIMS = [
    Claim("gain2", paper=4.0, rel_tol=1e-12, source="closed form"),
    Claim("steps", paper=100.0, band=(90.0, 110.0), source="Table 1"),
    Claim("missing", paper=1.0, abs_tol=0.1, source="Fig. 3"),
]
FAKE = Study(
    name="fake_new",
    description="a <fake> study",
    config=Config,
    run=_run,
    presets={"quick": {"steps": 10}, "tiny": {"steps": 1, "gain": 3.0}},
    claims=CLAIMS,
    assumptions={"gain": assumption(2.0, "why not")},
)


@pytest.fixture
def fake(monkeypatch):
    _run.calls.clear()

    def get_study(name):
        if name == FAKE.name:
            return FAKE
        raise ValueError(f"NAME: unknown study {name!r}")

    monkeypatch.setattr(registry, "get_study", get_study)
    monkeypatch.setattr(cli, "get_study", get_study)
    return _run


def test_claim_verdicts_and_tolerances():
    rows = check_claims(CLAIMS + [Claim("gain2", paper=4.1, abs_tol=0.05, rel_tol=0.01)], {"gain2": 4.0, "steps": 95.0})
    assert [r["verdict"] for r in rows] == ["reproduced", "reproduced", "not computed", "differs"]
    assert [r["tolerance"] for r in rows] == ["rel 1e-12", "band [90, 110]", "abs 0.1", "abs 0.05 + rel 0.01"]
    assert rows[2]["ours"] is None and rows[1]["source"] == "Table 1"
    # |4.0 − 4.1| = 0.1 > 0.05 + 0.041; and a NaN result differs
    assert Claim("x", paper=1.0, rel_tol=1.0).row({"x": float("nan")})["verdict"] == "differs"
    for bad, match in [
        (dict(), "give rel_tol and/or abs_tol, or band"),
        (dict(band=(1.0, 0.0)), r"band: need finite lo ≤ hi"),
        (dict(band=(0.0, 1.0), rel_tol=0.1), "band excludes"),
        (dict(rel_tol=-1.0), "rel_tol: must be finite and non-negative"),
    ]:
        with pytest.raises(ValueError, match=match):
            Claim("x", paper=1.0, **bad)


def test_config_resolution_preset_then_overrides():
    assert FAKE.resolve() == ("full", Config())
    assert FAKE.resolve("tiny", ["steps=7"]) == ("tiny", Config(gain=3.0, steps=7))
    with pytest.raises(ValueError, match="--preset huge: unknown preset of study 'fake_new'; known: full, quick, tiny"):
        FAKE.resolve("huge")
    with pytest.raises(ValueError, match="--set nope: unknown config key"):
        FAKE.resolve("quick", ["nope=1"])
    with pytest.raises(ValueError, match="preset 'quick' sets unknown config field"):
        Study("s", "", Config, _run, presets={"quick": {"stepz": 1}})

    @dataclass(frozen=True)
    class WithQuick:
        quick: bool = False

    with pytest.raises(ValueError, match="no `quick` field"):
        Study("s", "", WithQuick, _run)
    with pytest.raises(ValueError, match="expected an experiments.runner.Study, got dict"):
        as_study({"name": "old"})


def test_cli_runs_the_resolved_config_and_writes_the_reproduction_table(tmp_path, fake, capsys):
    out = tmp_path / "out"
    assert cli.main(["run", "fake_new", "--quick", "--set", "gain=2.5", "--out", str(out)]) == 0
    (ran,) = fake.calls
    assert ran == Config(gain=2.5, steps=10)  # the preset, then --set on top
    res = json.loads((out / "results.json").read_text())
    assert res["preset"] == "quick" and res["config"] == {"gain": 2.5, "steps": 10, "label": "a<b>"}
    assert res["assumptions"]["gain"]["why"] == "why not"
    verdicts = {r["metric"]: r["verdict"] for r in res["reproduction"]}
    assert verdicts == {"gain2": "differs", "steps": "differs", "missing": "not computed"}
    rows = list(csv.DictReader(open(out / "reproduction.csv")))
    assert [r["metric"] for r in rows] == ["gain2", "steps", "missing"] and rows[0]["ours"] == "6.25"
    assert "claim gain2: ours 6.25, paper 4 (rel 1e-12): differs" in capsys.readouterr().out
    assert cli.main(["run", "fake_new", "--preset", "nope", "--out", str(tmp_path / "o2")]) == 2
    assert "unknown preset" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # --preset and --quick exclude each other
        cli.main(["run", "fake_new", "--quick", "--preset", "tiny"])


def test_registry_is_lazy_and_a_broken_study_breaks_only_itself(tmp_path, monkeypatch, capsys):
    (tmp_path / "zz_broken_study.py").write_text("raise RuntimeError('this study is broken')\n")
    (tmp_path / "zz_tiny_study.py").write_text(
        "from experiments.runner import Study\nfrom tests.experiments.test_runner import Config, _run\n"
        "STUDY = Study('zz_tiny_study', 'tiny', Config, _run)\n"
    )
    monkeypatch.setattr(experiments, "__path__", [*experiments.__path__, str(tmp_path)])
    try:
        study = registry.get_study("zz_tiny_study")
        assert study.name == "zz_tiny_study" and "experiments.zz_broken_study" not in sys.modules
        studies, broken = registry.discover()
        assert "zz_tiny_study" in studies and "pid_tuning_comparison" in studies
        assert broken["zz_broken_study"] == "RuntimeError: this study is broken"
        assert cli.main(["list"]) == 0
        out = capsys.readouterr().out
        assert "zz_broken_study" in out and "BROKEN: RuntimeError: this study is broken" in out
        assert "presets: full, quick" in out
        with pytest.raises(RuntimeError, match="this study is broken"):  # its own error, when asked for
            registry.get_study("zz_broken_study")
    finally:
        for name in ("experiments.zz_broken_study", "experiments.zz_tiny_study"):
            sys.modules.pop(name, None)


class _Targets(HTMLParser):
    def __init__(self):
        super().__init__()
        self.images, self.links, self.ids, self.cells = [], [], set(), []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a["src"])
        if tag == "a":
            self.links.append(a["href"])
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "td" and "class" in a:
            self.cells.append(a["class"])


def test_html_report_links_and_images_resolve(tmp_path, fake, capsys):
    results = tmp_path / "results"
    assert cli.main(["run", "fake_new", "--out", str(results / "fake_new")]) == 0
    assert cli.main(["run", "fake_new", "--preset", "tiny", "--out", str(results / "fake_tiny")]) == 0
    (results / "not_a_study").mkdir()
    (results / "not_a_study" / "notes.txt").write_text("ignored")
    assert cli.main(["report", str(results)]) == 0
    page = (results / "report.html").read_text()
    parser = _Targets()
    parser.feed(page)
    assert len(parser.images) == 2 and {Path(s).name for s in parser.images} == {"line.png"}
    for target in parser.images + parser.links:
        if target.startswith("#"):
            assert target[1:] in parser.ids, target
        else:
            assert (results / target).is_file(), target
    assert any(t.endswith("reproduction.csv") for t in parser.links)
    assert "reproduced" in parser.cells and "not-computed" in parser.cells  # verdicts coloured
    assert "a &lt;fake&gt; study" in page and "<fake>" not in page  # text is escaped
    assert cli.main(["report", str(tmp_path / "nowhere")]) == 2
    assert "is not a folder" in capsys.readouterr().err


def test_paper_facts_are_read_from_toml_and_bad_files_are_named(tmp_path):
    (tmp_path / "s.toml").write_text(
        '[[claims]]\nmetric = "gain"\npaper = 2.0\nband = [1.5, 2.5]\nsource = "paper, Table 1"\n\n'
        '[assumptions.noise]\nvalue = [0.1, 0.2]\nwhy = "not given"\n'
    )
    claims, assumptions = paper_facts("s", tmp_path)
    assert claims == [Claim("gain", paper=2.0, band=(1.5, 2.5), source="paper, Table 1")]
    assert assumptions == {"noise": {"value": [0.1, 0.2], "why": "not given"}}
    (tmp_path / "bad.toml").write_text('[[claims]]\nmetric = "g"\npaper = 1.0\nrel_tol = 0.1\nsorce = "typo"\n')
    with pytest.raises(ValueError, match=r"bad.toml: claims\[0\] has unknown field\(s\) sorce"):
        paper_facts("bad", tmp_path)
    (tmp_path / "bad2.toml").write_text("[assumptions.x]\nvalue = 1\n")
    with pytest.raises(ValueError, match="assumptions.x must have exactly 'value' and 'why'"):
        paper_facts("bad2", tmp_path)
    with pytest.raises(ValueError, match="paper facts of study 'absent': cannot read"):
        paper_facts("absent", tmp_path)


def test_every_paper_file_belongs_to_a_study_and_loads():
    for path in sorted(PAPERS.glob("*.toml")):
        assert (PAPERS.parent / f"{path.stem}.py").exists(), path
        claims, assumptions = paper_facts(path.stem)
        assert assumptions and all(a["why"] for a in assumptions.values()), path
