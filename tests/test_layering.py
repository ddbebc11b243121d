"""Layers point down (DESIGN.md principle 12, issue 16 "Layers"): checked on the import statements of
every module, parsed with ``ast`` (nothing is imported), including imports inside functions.

    jaxsim.core                                   imports nothing above it
    jaxsim.plants | jaxsim.control | jaxsim.estimation | jaxsim.inertial
                                                  plants import neither estimation nor control;
                                                  estimation does not import plants; inertial
                                                  (sensor models) neither plants nor control
    jaxsim.problem                                core, plants, control, estimation and
                                                  montecarlo.distributions only
    optim, jaxsim.montecarlo, jaxsim.envs         never import experiments
    experiments                                   (anything)
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.conftest import ROOT

ABOVE_CORE = (
    "jaxsim.plants",
    "jaxsim.control",
    "jaxsim.estimation",
    "jaxsim.inertial",
    "jaxsim.problem",
    "jaxsim.montecarlo",
    "jaxsim.envs",
    "jaxsim.mjx",
    "optim",
    "experiments",
)

# (modules under this package, imports they must not make)
RULES: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("jaxsim", ("experiments",)),
    ("optim", ("experiments",)),
    ("jaxsim.core", ABOVE_CORE),
    ("jaxsim.plants", ("jaxsim.estimation", "jaxsim.control")),
    ("jaxsim.estimation", ("jaxsim.plants",)),
    ("jaxsim.inertial", ("jaxsim.plants", "jaxsim.control", "jaxsim.problem", "jaxsim.montecarlo")),
    ("jaxsim.problem", ("jaxsim.envs", "jaxsim.mjx", "jaxsim.montecarlo", "optim", "experiments")),
)
# imports a rule's forbidden prefix would catch but the layers allow: (package, allowed prefix)
EXCEPTIONS = {"jaxsim.problem": ("jaxsim.montecarlo.distributions",)}


def module_name(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported_modules(source: str, module: str, is_package: bool = False) -> set[str]:
    """Every module ``module``'s source names in an import: ``import a.b`` → ``a.b``;
    ``from a import b`` → ``a.b`` (``b`` a submodule or a name of ``a``; ``import *`` → ``a``);
    relative imports resolved."""
    found: set[str] = set()
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            found.update(base if alias.name == "*" else f"{base}.{alias.name}" for alias in node.names)
    return found


def _within(name: str, prefix: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def violations(module: str, imports: set[str]) -> list[str]:
    """``"module imports name (rule: package must not import prefix)"`` for every broken rule."""
    out = []
    for package, forbidden in RULES:
        if not _within(module, package):
            continue
        allowed = EXCEPTIONS.get(package, ())
        for name in sorted(imports):
            if any(_within(name, ok) for ok in allowed):
                continue
            for prefix in forbidden:
                if _within(name, prefix):
                    out.append(f"{module} imports {name} ({package} must not import {prefix})")
    return out


def _library_modules() -> list[Path]:
    return sorted(p for top in ("jaxsim", "optim") for p in (ROOT / top).rglob("*.py"))


def test_the_checker_finds_what_it_must():
    """The rules bite: a synthetic module breaking each one is flagged (so the tree test can fail)."""
    cases = {
        ("jaxsim.envs.x", "from experiments.trms_problem import TRMSTuning"): "experiments",
        ("optim.x", "import experiments"): "experiments",
        ("jaxsim.plants.x", "def f():\n    from jaxsim.estimation.smo import ReducedModel"): "jaxsim.estimation",
        ("jaxsim.plants.x", "from jaxsim import control"): "jaxsim.control",
        ("jaxsim.estimation.x", "from ..plants.marine import rotation_z"): "jaxsim.plants",
        ("jaxsim.core.x", "from jaxsim.montecarlo import engine"): "jaxsim.montecarlo",
        ("jaxsim.problem.x", "from optim import tune"): "optim",
        ("jaxsim.problem.x", "from jaxsim.montecarlo import normal"): "jaxsim.montecarlo",
        ("jaxsim.core.x", "from jaxsim.plants.marine import *"): "jaxsim.plants",
    }
    for (module, source), prefix in cases.items():
        found = violations(module, imported_modules(source, module))
        assert found and all(f"must not import {prefix})" in v for v in found), (module, source, found)
    allowed = {
        ("jaxsim.control.x", "from jaxsim.plants import auv"),
        ("jaxsim.estimation.x", "from jaxsim.control.kalman_gain import discrete_kalman"),
        ("jaxsim.problem.x", "from jaxsim.montecarlo.distributions import normal"),
        ("jaxsim.problem.x", "from jaxsim.montecarlo import distributions"),
        ("jaxsim.core.x", "from jaxsim.precision import enable_x64_from_env"),
    }
    for module, source in allowed:
        assert violations(module, imported_modules(source, module)) == [], (module, source)


@pytest.mark.parametrize("path", _library_modules(), ids=lambda p: str(p.relative_to(ROOT)))
def test_library_modules_respect_the_layers(path: Path):
    module = module_name(path)
    imports = imported_modules(path.read_text(encoding="utf-8"), module, path.name == "__init__.py")
    assert violations(module, imports) == []
