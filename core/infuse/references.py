"""Where a file's references to other files may lead.

Models and packs name other files: glTF buffers and images, COLLADA images, FBX media, a pack
manifest's clips. A reference resolves only to a regular file inside the referencing file's folder (or
below it): no absolute paths, no ``..`` out of the folder, no links that lead out of it, and never a
device, pipe or folder, so that a downloaded model cannot read other local files into an output that
is then shared. The user may allow references outside the folder (still only to regular files) with
the setting ``INFUSE_ALLOW_EXTERNAL=1``, ``infuse.load(path, allow_external=True)`` or
:func:`allow_external`.
"""
from __future__ import annotations

import contextvars
import os
from contextlib import contextmanager
from pathlib import Path

from .errors import ExternalReferenceError, InputError

_ALLOWED = contextvars.ContextVar("infuse_allow_external", default=False)
SETTING = "INFUSE_ALLOW_EXTERNAL"


def external_allowed() -> bool:
    """Whether references may lead outside the referencing file's folder."""
    return _ALLOWED.get() or os.environ.get(SETTING, "").strip().lower() in ("1", "true", "yes")


@contextmanager
def allow_external(allowed: bool = True):
    """Within the block, references may (or may not) lead outside the referencing file's folder."""
    token = _ALLOWED.set(allowed)
    try:
        yield
    finally:
        _ALLOWED.reset(token)


def inside(referrer: str | Path, reference: str, place: str, what: str = "file") -> Path:
    """The path ``reference`` (relative to ``referrer``'s folder) names, checked to stay in that folder
    (unless allowed) and, when something is there, to be a regular file; it need not exist yet.

    Raises :class:`~infuse.errors.ExternalReferenceError` for a reference out of the folder or to
    something that is not a regular file."""
    referrer = Path(referrer)
    if not reference or "\x00" in reference:
        raise InputError(referrer, place, f"{what} reference {reference!r} is not a file name")
    folder = referrer.parent.resolve()
    named = Path(reference)
    if not external_allowed():
        if named.is_absolute():
            raise ExternalReferenceError(referrer, place, f"{what} {reference!r} is an absolute path; only files in "
                                         f"the file's own folder are read (set {SETTING}=1 to allow)")
    try:
        target = (folder / named).resolve()
    except (OSError, RuntimeError) as exc:  # a link loop
        raise ExternalReferenceError(referrer, place, f"{what} {reference!r} cannot be resolved: {exc}") from None
    if not external_allowed() and not target.is_relative_to(folder):
        raise ExternalReferenceError(referrer, place, f"{what} {reference!r} leads out of the file's folder "
                                     f"(set {SETTING}=1 to allow)")
    if target.exists() and not target.is_file():
        raise ExternalReferenceError(referrer, place, f"{what} {reference!r} is not a regular file")
    return target


def resolve(referrer: str | Path, reference: str, place: str, what: str = "file") -> Path:
    """The regular file that ``reference`` (a path, relative to ``referrer``'s folder) names.

    Raises :class:`~infuse.errors.ExternalReferenceError` for a reference out of the folder (unless
    allowed) or to something that is not a regular file, :class:`~infuse.errors.InputError` for a
    missing one."""
    target = inside(referrer, reference, place, what)
    if not target.exists():
        raise InputError(referrer, place, f"missing {what} {reference!r}")
    return target


def read(referrer: str | Path, reference: str, place: str, what: str = "file", max_bytes: int | None = None) -> bytes:
    """The bytes of :func:`resolve`'s file, at most ``max_bytes`` of them."""
    target = resolve(referrer, reference, place, what)
    try:
        with open(target, "rb") as stream:
            return stream.read(-1 if max_bytes is None else max_bytes)
    except OSError as exc:
        raise InputError(referrer, place, f"cannot read {what} {reference!r}: {exc.strerror or exc}") from None
