"""Distribution names and the ``pyproject.toml`` of a new project.

The core is published as ``infuse-anim`` (its import name is ``infuse``); every plugin, pack and
example as ``infuse-anim-<name>`` (packs ``infuse-anim-pack-<name>``), importing ``infuse_<name>``
(packs ``infuse_pack_<name>``). A project depends on the core by a compatible-release specifier on
the running version: ``infuse-anim~=0.1.0`` accepts 0.1.x, the releases that keep 0.1's pack and
plugin formats.
"""
from __future__ import annotations

import json
import re

from .. import __version__
from ..errors import UsageError

#: The core's distribution name on the package index.
CORE_DISTRIBUTION = "infuse-anim"
#: A licence expression that builds but says nothing: the author replaces it (see the generated README).
LICENSE_PLACEHOLDER = "LicenseRef-Unspecified"
_NAME = re.compile(r"[a-z][a-z0-9]*(-[a-z0-9]+)*")
_VERSION = re.compile(r"\d+(\.\d+)*((a|b|rc)\d+)?(\.post\d+)?(\.dev\d+)?")


def core_requirement(version: str = __version__) -> str:
    """The dependency on the core for a project made with infuse ``version``: ``infuse-anim~=X.Y.0``."""
    major, minor = version.split(".")[:2]
    return f"{CORE_DISTRIBUTION}~={major}.{minor}.0"


def check_name(name: str, what: str = "name") -> str:
    """``name`` if it is lower-case letters and digits in hyphen-separated words (``bandai-fem``), else UsageError."""
    if not _NAME.fullmatch(name or ""):
        raise UsageError(f"{what} {name!r}: use lower-case letters and digits in words joined by hyphens, "
                         "starting with a letter (e.g. 'bandai-fem')")
    return name


def check_version(version: str) -> str:
    """``version`` if it is a public release number the package index takes (``1.2.0``, ``0.1.0rc1``), else UsageError."""
    if not _VERSION.fullmatch(version or ""):
        raise UsageError(f"version {version!r}: expected a release number such as 0.1.0 (PEP 440)")
    return version


def check_description(text: str | None) -> str | None:
    """``text`` if it is one printable line without backslashes or double quotes (it goes into TOML, Markdown
    and Python docstrings), else UsageError; None passes."""
    if text is not None and (not text.strip() or not text.isprintable() or any(c in text for c in '\\"')):
        raise UsageError(f"description {text!r}: one printable line without backslashes or double quotes")
    return text


def distribution_name(name: str, pack: bool = False) -> str:
    """``infuse-anim-<name>``, or ``infuse-anim-pack-<name>`` for a behaviour pack."""
    return f"{CORE_DISTRIBUTION}-{'pack-' if pack else ''}{check_name(name)}"


def package_name(name: str, pack: bool = False) -> str:
    """The import package: ``infuse_<name>``, or ``infuse_pack_<name>`` (hyphens become underscores)."""
    return f"infuse_{'pack_' if pack else ''}{check_name(name).replace('-', '_')}"


def _string(value: str) -> str:
    """A TOML basic string (JSON's escapes are TOML's: quotes, backslashes, control characters)."""
    return json.dumps(value, ensure_ascii=False)


def _strings(values) -> str:
    return "[" + ", ".join(_string(v) for v in values) + "]"


def pyproject_text(name: str, version: str, description: str, package: str, entry_points: dict[str, dict[str, str]], *,
                   dependencies: tuple[str, ...] = (), package_data: tuple[str, ...] = (),
                   license: str = LICENSE_PLACEHOLDER, license_files: tuple[str, ...] = ()) -> str:
    """The ``pyproject.toml`` of a project: distribution ``name`` holding import package ``package``,
    depending on the core (:func:`core_requirement`) and ``dependencies``, registering ``entry_points``
    (group -> entry-point name -> module), shipping ``package_data`` (globs inside the package)."""
    lines = ["[build-system]", 'requires = ["setuptools>=77", "wheel"]', 'build-backend = "setuptools.build_meta"', "",
             "[project]", f"name = {_string(name)}", f"version = {_string(version)}", f"description = {_string(description)}",
             'readme = "README.md"', 'requires-python = ">=3.11"',
             "# The licence of what you publish (for a pack, the clips' licence) as an SPDX expression, e.g. \"CC-BY-4.0\".",
             f"license = {_string(license)}"]
    if license_files:
        lines.append(f"license-files = {_strings(license_files)}")
    lines += [f"dependencies = {_strings((core_requirement(),) + tuple(dependencies))}", "",
              "[project.optional-dependencies]", 'test = ["pytest>=7"]']
    for group, points in entry_points.items():
        lines += ["", f'[project.entry-points."{group}"]'] + [f"{k} = {_string(v)}" for k, v in points.items()]
    lines += ["", "[tool.setuptools.packages.find]", f"include = {_strings([package + '*'])}"]
    if package_data:
        lines += ["", "[tool.setuptools.package-data]", f"{package} = {_strings(package_data)}"]
    return "\n".join(lines) + "\n"
