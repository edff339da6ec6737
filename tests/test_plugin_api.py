"""The plugins, examples and packs of this repository keep to the public plugin API (:mod:`infuse.api`):
they import infuse only from its public modules, and no other plugin."""
from __future__ import annotations

import ast
import importlib.util
from pathlib import Path

from infuse.api import PUBLIC_MODULES, is_public

ROOT = Path(__file__).resolve().parents[1]
PLUGIN_FOLDERS = ("plugins", "examples", "behaviour_libs")


def plugin_packages() -> dict[str, Path]:
    """Import package name -> its folder, for every distribution folder of the repository."""
    out = {}
    for top in PLUGIN_FOLDERS:
        for dist in sorted([*(ROOT / top).glob("*/pyproject.toml"), *(ROOT / top).glob("*/*/pyproject.toml")]):
            for package in sorted(dist.parent.glob("*/__init__.py")):
                if "build" not in package.parent.relative_to(ROOT).parts:
                    out[package.parent.name] = package.parent
    return out


def imported_modules(path: Path, package: str) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import in ``path``, a module of ``package``."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative: inside the plugin's own package
                continue
            base = node.module or ""
            out.append((node.lineno, base))
            if base == "infuse":  # "from infuse import quaternions" imports a submodule
                out += [(node.lineno, f"infuse.{a.name}") for a in node.names
                        if importlib.util.find_spec(f"infuse.{a.name}") is not None]
    return out


def test_every_public_module_exists():
    assert [m for m in PUBLIC_MODULES if importlib.util.find_spec(m) is None] == []


def _imports_of_plugins():
    """(where, module, the importing package, every plugin package) for every import in the plugin packages."""
    packages = plugin_packages()
    assert {"infuse_bvh", "infuse_gaze", "infuse_example_mapper", "infuse_pack_reaching"} <= set(packages)
    for package, folder in packages.items():
        for path in sorted(folder.rglob("*.py")):
            for line, module in imported_modules(path, package):
                yield f"{path.relative_to(ROOT)}:{line}", module, package, packages


def test_plugins_import_only_the_public_api():
    problems = [f"{where}: {module} is not public (infuse.api)" for where, module, _, _ in _imports_of_plugins()
                if module.split(".")[0] == "infuse" and not is_public(module)]
    assert problems == [], "\n".join(problems + ["(make the module public in infuse/api.py, or import a public one)"])


def test_no_plugin_imports_another():
    problems = [f"{where}: {package} imports {module}" for where, module, package, packages in _imports_of_plugins()
                if module.split(".")[0] in packages and module.split(".")[0] != package]
    assert problems == [], "\n".join(problems + ["(what two plugins share belongs in the core, behind infuse.api)"])


def test_the_scene_and_runtime_name_no_controller_kind():
    """The core realizes behaviours through the registry and the stage: its scene and runtime packages name
    none of the built-in controller kinds (a plugin realizes its own, and a third party may replace it)."""
    import re

    kinds = re.compile(r"\b(locomotion|reach|gaze|blink|breathing|lipsync)\b")
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for folder in ("scene", "runtime") for path in sorted((ROOT / "core/infuse" / folder).glob("*.py"))
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1) if kinds.search(line)]
    assert not found, found
