"""``infuse pack new``: a pack project, the folder that ``infuse pack build --wheel`` and ``pip install`` take as it is.

::

    NAME/
      pyproject.toml                 distribution infuse-anim-pack-NAME, entry point NAME (infuse.behaviour_packs)
      README.md                      what the pack holds, how to install and use it, the builder's figures
      LICENSE                        the source's licence file, when one lies beside the clips
      infuse_pack_NAME/plugin.py     registers pack/manifest.toml
      infuse_pack_NAME/pack/         manifest.toml, the skeleton, clips/, analysis.json and .npz (built)
      tests/test_pack_NAME.py        the installed pack is listed, built, and infuses onto the canonical skeleton

The pack folder is self-contained (:mod:`infuse.packs.folder`). The README's figures sit between two
markers and ``infuse pack build`` rewrites them whenever it rebuilds the pack.
"""
from __future__ import annotations

import importlib.util
import re
import shutil
from pathlib import Path
from string import Template

from ..errors import UsageError
from ..scaffold.distribution import (LICENSE_PLACEHOLDER, check_description, check_version, distribution_name, package_name,
                                     pyproject_text)
from .build import build_pack, summary
from .folder import copy_pack
from .importers import FIRST_VERSION, import_bvh_folder, import_smartbody
from .manifest import read_manifest
from .pack import Pack, installed_packs

IMPORT_KINDS = ("bvh", "smartbody")
PACK_DATA = ("pack/**/*",)  # every file under pack/, in any subfolder
FIGURES_START = "<!-- figures: written by infuse pack build -->"
FIGURES_END = "<!-- end of figures -->"
_LICENCE_FILE = re.compile(r"(LICEN[CS]E|COPYING)([.-].*)?", re.IGNORECASE)
#: How many folders above a source a licence file is looked for (a dataset's root above its data/ folder).
LICENCE_SEARCH_DEPTH = 3

PLUGIN = Template('''"""Registers the $name behaviour pack's manifest under the ``infuse.behaviour_packs`` entry-point group."""
from pathlib import Path

from infuse import hookimpl
from infuse.plugin_types import BehaviourPack

MANIFEST = Path(__file__).resolve().parent / "pack" / "manifest.toml"


def load():
    from infuse.packs import load_pack

    return load_pack(MANIFEST)


@hookimpl
def infuse_behaviour_packs():
    return [BehaviourPack($name_literal, load, $description_literal, str(MANIFEST))]
''')

TEST = Template('''"""The installed $name pack: listed, built from its clips as they are, and infused onto a skeleton."""
import infuse
from infuse.canonical import canonical_skeleton
from infuse.packs import infuse_character, installed_packs, load_pack


def test_installed_and_built():
    assert $name_literal in installed_packs()
    pack = load_pack($name_literal)
    assert pack.built, "run 'infuse pack build' after changing the clips or the manifest"
    assert len(pack.analysis["clips"]) == len(pack.manifest.clips)
    assert pack.analysis["tessellations"], "no blend space: the clips give no parameter range"


def test_infuses_onto_the_canonical_skeleton(tmp_path):
    character = infuse.Character("canonical", infuse.Asset(None, "bvh", canonical_skeleton()))
    infusion = infuse_character(character, [$name_literal], cache=tmp_path)
    space = infusion.spaces[$name_literal]
    assert len(space.clips) == len(load_pack($name_literal).manifest.clips)
    assert all(t.dimension >= 1 for t in space.tessellations.values())
''')

README = Template('''# $distribution

The `$name` behaviour pack for infuse ($kind): $description.

## Install

```sh
$install
```

It depends on the `infuse-anim` distribution (the `infuse` command and Python package).

## Use

```sh
$use
```

```python
import infuse
from infuse.runtime import Runtime, controller

rt = Runtime(fps=30)
bob = rt.add_character(infuse.Character("bob", infuse.load("character.glb")))
rt.activate(bob, $usage, 0.0)
rt.run(4.0)
infuse.save(rt.export(bob, "$name"), "$name.glb")
```

## Source and licence

$source

The licence is set by `license` in `pyproject.toml` (an SPDX expression such as `CC-BY-4.0`);
it must allow you to publish the clips.$licence_note

## Measured by `infuse pack build`

$figures_start
$figures
$figures_end

## A new release

Change the clips or `$package/pack/manifest.toml`, raise `version` in the manifest and in
`pyproject.toml` alike, then:

```sh
$release
```
''')

USAGE = {
    "locomotion": 'controller("locomotion", pack="{name}", speed=1.2)',
    "reach": 'controller("reach", target=(-0.3, 1.2, 0.4), hand="right", pack="{name}")',
    "gesture": 'controller("gesture", clip="<clip>", pack="{name}")',
    "posture": 'controller("posture", clip="<clip>", pack="{name}")',
}

GITIGNORE = "build/\ndist/\n*.egg-info/\n__pycache__/\n"


def _commands(rows: list[tuple[str, str]]) -> str:
    """Shell lines with their comments aligned."""
    width = max(len(command) for command, _ in rows)
    return "\n".join(f"{command:<{width}}  # {comment}" if comment else command for command, comment in rows)


def find_licence(folder: Path) -> Path | None:
    """The first licence file (LICENSE, LICENCE, COPYING...) in ``folder`` or up to :data:`LICENCE_SEARCH_DEPTH` above it."""
    for d in [folder, *folder.parents][:LICENCE_SEARCH_DEPTH + 1]:
        found = sorted(p for p in d.iterdir() if p.is_file() and _LICENCE_FILE.fullmatch(p.name)) if d.is_dir() else []
        if found:
            return found[0]
    return None


def figures_block(pack: Pack) -> str:
    """What the builder measured, as a README text block."""
    return f"```text\n{summary(pack)}\n```"


def refresh_figures(readme: Path, pack: Pack) -> bool:
    """Rewrite the figures between the README's markers; False when it has no markers (nothing written)."""
    if not readme.is_file():
        return False
    text = readme.read_text(encoding="utf-8")
    start, end = text.find(FIGURES_START), text.find(FIGURES_END)
    if start < 0 or end < start:
        return False
    new = text[:start + len(FIGURES_START)] + "\n" + figures_block(pack) + "\n" + text[end:]
    if new != text:
        readme.write_text(new, encoding="utf-8")
    return True


def pack_manifests(project: Path) -> list[Path]:
    """The pack manifests inside a project's import packages (``*/pack/manifest.toml``)."""
    return sorted(p.resolve() for p in project.glob("*/pack/manifest.toml") if not p.parts[-3].startswith((".", "build")))


def new_pack_project(name: str, *, from_folder=None, import_kind: str | None = None, source=None, pattern: str = "*.bvh",
                     clip_kind: str = "locomotion", dest=None, version: str | None = None, description: str | None = None,
                     license: str | None = None, mapper: str | None = None) -> tuple[Path, Pack]:
    """Make the project ``dest`` (default ``./NAME``) of pack ``name`` from a pack folder (``from_folder``) or by
    importing ``source`` (``import_kind`` ``"bvh"`` with ``pattern`` and ``clip_kind``, or ``"smartbody"``), build the pack and
    write the README with its figures. Returns the project folder and the built pack."""
    distribution, package = distribution_name(name, pack=True), package_name(name, pack=True)
    if (from_folder is None) == (import_kind is None):
        raise UsageError("give either a pack folder to start from or a source to import, not both")
    if import_kind is not None and import_kind not in IMPORT_KINDS:
        raise UsageError(f"cannot import {import_kind!r}; expected one of {', '.join(IMPORT_KINDS)}")
    if version is not None:
        check_version(version)
    check_description(description)
    if name in installed_packs():
        raise UsageError(f"a behaviour pack named {name!r} is already installed; choose another name")
    if importlib.util.find_spec(package) is not None:
        raise UsageError(f"an import package {package!r} is already installed; choose another name")
    project = Path(dest if dest is not None else name)
    if project.exists() and (not project.is_dir() or any(project.iterdir())):
        raise UsageError(f"{project}: already exists and is not an empty folder")
    origin = Path(from_folder if from_folder is not None else source).resolve()
    if project.resolve() == origin or project.resolve() in origin.parents:
        raise UsageError(f"{project}: the project must not contain its source {origin}")
    pack_folder = project / package / "pack"
    try:
        if from_folder is not None:
            manifest = copy_pack(from_folder, pack_folder, name=name, version=version, description=description)
            where = f"Copied from the pack `{read_manifest(from_folder).name}` (folder `{origin.name}`)."
        elif import_kind == "bvh":
            manifest = import_bvh_folder(source, pack_folder, name=name, pattern=pattern, kind=clip_kind,
                                         version=version or FIRST_VERSION, description=description)
            where = f"Clips copied from the folder `{origin.name}` (`{pattern}`)."
        else:
            manifest = import_smartbody(source, pack_folder, name=name, version=version or FIRST_VERSION,
                                        description=description)
            where = f"Copied from the SmartBody behaviour set `{origin.name}`."
        check_version(read_manifest(manifest).version)
        pack = build_pack(manifest, mapper=mapper)
    except BaseException:
        shutil.rmtree(project, ignore_errors=True)
        raise
    licence = find_licence(origin if origin.is_dir() else origin.parent)
    licence_files: tuple[str, ...] = ()
    note = ""
    if licence is not None:
        shutil.copyfile(licence, project / "LICENSE")
        licence_files = ("LICENSE",)
        note = (f" `LICENSE` is the licence file found with the source (`{licence.name}`); set `license` to the"
                " expression it corresponds to.")
    m = pack.manifest
    wheel = distribution.replace("-", "_")
    (project / package / "__init__.py").write_text(f'"""The {name} behaviour pack for infuse: data in ``pack/``, registered by ``plugin.py``."""\n',
                                                   encoding="utf-8")
    (project / package / "plugin.py").write_text(PLUGIN.substitute(name=name, name_literal=repr(name),
                                                                    description_literal=repr(m.description or name)), encoding="utf-8")
    (project / "tests").mkdir(exist_ok=True)
    test_file = project / "tests" / f"test_{package.removeprefix('infuse_')}.py"
    test_file.write_text(TEST.substitute(name=name, name_literal=repr(name)), encoding="utf-8")
    (project / "pyproject.toml").write_text(pyproject_text(
        distribution, m.version, f"The {name} behaviour pack for infuse: {m.description or m.kind}", package,
        {"infuse.behaviour_packs": {name: f"{package}.plugin"}}, package_data=PACK_DATA,
        license=license or LICENSE_PLACEHOLDER, license_files=licence_files), encoding="utf-8")
    (project / ".gitignore").write_text(GITIGNORE, encoding="utf-8")
    (project / "README.md").write_text(README.substitute(
        distribution=distribution, name=name, kind=m.kind, description=m.description or f"a {m.kind} pack",
        install=_commands([(f"pip install {distribution}", "once published on the package index"),
                           (f"pip install dist/{wheel}-{m.version}-py3-none-any.whl", "the wheel 'infuse pack build --wheel' writes")]),
        use=_commands([("infuse packs", f"lists {name}"), (f"infuse pack show {name}", "clips, parameters, blend spaces, checks"),
                       (f"infuse infuse character.glb --packs {name}", "the pack retargeted onto a character, cached")]),
        release=_commands([("infuse pack build --wheel", "analyses the clips again, checks, writes dist/*.whl"),
                           *([(f"infuse pack test {package}/pack --on character.glb",
                               "speeds, drift and foot skate measured on a character")] if m.kind == "locomotion" else []),
                           (f"pip install dist/{wheel}-VERSION-py3-none-any.whl", ""), ("pytest tests", "")]),
        package=package, source=where, licence_note=note,
        usage=USAGE[m.kind].format(name=name), figures_start=FIGURES_START, figures=figures_block(pack),
        figures_end=FIGURES_END), encoding="utf-8")
    return project, pack

