"""``infuse plugin new KIND NAME``: a plugin project that installs, shows in ``infuse plugins`` and tests itself.

::

    NAME/
      pyproject.toml           distribution infuse-anim-NAME, entry point NAME in the kind's group
      README.md                what it does, how to install, test and publish it
      infuse_NAME/plugin.py    a small working plugin of the kind (see :mod:`infuse.scaffold.templates`)
      tests/test_NAME.py       its tests: installed, and doing what it says
"""
from __future__ import annotations

import importlib.util
from pathlib import Path
from string import Template

from .. import registry
from ..errors import UsageError
from .distribution import check_description, distribution_name, package_name, pyproject_text
from .templates import KINDS

README = Template('''# $distribution

An infuse $kind plugin, `$name`: $summary.

## Install and test

```sh
pip install -e .                 # into the environment where infuse (distribution infuse-anim) is
infuse plugins                   # lists $name ($kind, $distribution)
pip install -e '.[test]' && pytest tests
```

Then:

```sh
$usage
```

## Publish

Set `license` in `pyproject.toml`, raise `version` for each release, then build the wheel and upload it:

```sh
pip wheel --no-deps -w dist .
```

The plugin is `$package/plugin.py`: change it, keep its tests passing. It depends on `infuse-anim`
(import name `infuse`), imports only the modules `infuse.api` lists as public, and nothing of another
plugin.
''')

GITIGNORE = "build/\ndist/\n*.egg-info/\n__pycache__/\n"


def identifier(name: str) -> str:
    """``tip-head`` -> ``TipHead``: a class name from a plugin name."""
    return "".join(word.capitalize() for word in name.split("-"))


def new_plugin_project(kind: str, name: str, dest=None, description: str | None = None) -> Path:
    """Write the project of plugin ``name`` of ``kind`` into ``dest`` (default ``./NAME``); returns its folder."""
    if kind == "behaviour-pack":
        raise UsageError("a behaviour pack is data: make its project with 'infuse pack new NAME --from FOLDER | --import KIND SRC'")
    if kind not in KINDS:
        raise UsageError(f"unknown plugin kind {kind!r}; expected one of {', '.join(KINDS)}")
    distribution, package = distribution_name(name), package_name(name)
    check_description(description)
    if importlib.util.find_spec(package) is not None:
        raise UsageError(f"an import package {package!r} is already installed; choose another name")
    if name in registry.table(kind):
        raise UsageError(f"a {kind} named {name!r} is already installed; choose another name")
    project = Path(dest if dest is not None else name)
    if project.exists() and (not project.is_dir() or any(project.iterdir())):
        raise UsageError(f"{project}: already exists and is not an empty folder")
    template = KINDS[kind]
    values = {"name": name, "package": package, "distribution": distribution, "ident": identifier(name), "extension": f".{name}"}
    summary = description or Template(template.summary).substitute(values)
    (project / package).mkdir(parents=True)
    (project / "tests").mkdir()
    (project / package / "__init__.py").write_text(f'"""{distribution}: {summary}."""\n', encoding="utf-8")
    for filename, source in template.modules.items():
        (project / package / filename).write_text(source.substitute(values), encoding="utf-8")
    (project / "tests" / f"test_{package.removeprefix('infuse_')}.py").write_text(template.test.substitute(values),
                                                                                encoding="utf-8")
    (project / "pyproject.toml").write_text(pyproject_text(
        distribution, "0.1.0", f"infuse {kind} plugin {name}: {summary}", package,
        {template.group: {name: f"{package}.plugin"}}), encoding="utf-8")
    (project / "README.md").write_text(README.substitute(values, kind=kind, summary=summary,
                                                         usage=Template(template.usage).substitute(values)), encoding="utf-8")
    (project / ".gitignore").write_text(GITIGNORE, encoding="utf-8")
    return project
