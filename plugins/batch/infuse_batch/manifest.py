"""The output tree's record of finished work, so that a batch run again skips it.

``OUTDIR/.infuse-batch.jsonl`` holds one JSON line per finished unit: for each (character, input)
done, the settings, a signature of each input file (size, modification time in nanoseconds,
SHA-256) and the output files (relative to OUTDIR). Only the job's driver appends to it, once a
unit's outputs are all in place (each output is itself written atomically), so a job stopped at any
point leaves a manifest that names only complete files; a torn last line is ignored.

A (character, input) pair is skipped when its latest entry has the same settings, every output it
names exists, and each input file still matches its signature: same size and time, or, when only
the time changed, the same SHA-256.
"""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

from .jobs import Settings, Source

FILENAME = ".infuse-batch.jsonl"


def sha256(path: str | Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def signature(path: str | Path) -> dict:
    """``{"path", "size", "mtime_ns", "sha256"}`` of a file (stat first: a file changed while it is
    hashed then fails the time check on the next run rather than passing it)."""
    st = os.stat(path)
    return {"path": str(path), "size": st.st_size, "mtime_ns": st.st_mtime_ns, "sha256": sha256(path)}


def packs_input(settings: Settings) -> str:
    """The manifest's input name for an infusion with the settings' packs."""
    return "packs:" + ",".join(settings.packs)


class Manifest:
    """Finished (character, input) pairs of an output folder (see the module docstring)."""

    def __init__(self, out: str | Path, resume: bool = True):
        self.out = Path(out)
        self.path = self.out / FILENAME
        self.entries: dict[tuple[str, str], dict] = {}
        self._hashes: dict[str, str | None] = {}
        if resume and self.path.is_file():
            with open(self.path, encoding="utf-8") as f:
                for line in f:
                    try:
                        doc = json.loads(line)
                    except json.JSONDecodeError:
                        continue  # a line torn by a stopped job
                    for e in doc.get("done", []) if isinstance(doc, dict) else []:
                        self.entries[(e["character"], e["input"])] = e

    def _matches(self, sig: dict | None, path: str) -> bool:
        if not sig or sig.get("path") != path:
            return False
        try:
            st = os.stat(path)
        except OSError:
            return False
        if st.st_size != sig["size"]:
            return False
        if st.st_mtime_ns == sig["mtime_ns"]:
            return True
        if path not in self._hashes:
            self._hashes[path] = sha256(path)
        return self._hashes[path] == sig["sha256"]

    def done(self, character: Source, motion: Source | None, settings: Settings, packs: dict | None = None) -> bool:
        """Whether ``motion`` onto ``character`` (or, with ``motion=None``, the infusion with the
        settings' packs, whose versions and fingerprints are ``packs``) is already in the output tree."""
        entry = self.entries.get((character.name, motion.name if motion is not None else packs_input(settings)))
        if entry is None or entry.get("settings") != settings.key():
            return False
        if not entry["outputs"] or not all((self.out / o).is_file() for o in entry["outputs"]):
            return False
        files = entry.get("files", {})
        if not self._matches(files.get("character"), character.path):
            return False
        if motion is None:
            return files.get("packs") == packs
        return self._matches(files.get("input"), motion.path)

    def record(self, done: list[dict]) -> None:
        """Append one unit's finished pairs (each a dict with ``character``, ``input``,
        ``settings``, ``files`` and ``outputs``)."""
        if not done:
            return
        self.out.mkdir(parents=True, exist_ok=True)
        with open(self.path, "a", encoding="utf-8") as f:
            f.write(json.dumps({"done": done}, sort_keys=True) + "\n")
        for e in done:
            self.entries[(e["character"], e["input"])] = e
