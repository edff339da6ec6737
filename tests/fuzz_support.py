"""Mutation fuzzing of everything infuse reads: seeds, mutations, and the outcome of one case.

A case is a format, the bytes of the file under test and the files beside it (an ``.asf`` for an
``.amc``, a ``.bin`` for a ``.gltf``). Seeds are valid files: small ones built here, and files of
the corpus and the wild set read in place. A mutation is a list of operations ``(kind, where, n)``
(``where`` in [0, 1] picks the place, ``n`` the payload), drawn by Hypothesis in the quick test run
and by a seeded :class:`random.Random` in ``benchmarks/fuzz.py``.

Each case runs in a :class:`Worker`, a child process with an address-space limit, under a wall-clock
limit, and ends in one outcome class:

- ``typed error``: ``infuse info --json`` (or the BML scheduler, or the scene reader) answered exit
  code 2 or 3 with one ``infuse: error:`` line naming the file;
- ``load``: read, every number finite, written back as glTF and BVH and read again;
- ``untyped``: anything else raised (a bug), or an error line that is not one line naming the file;
- ``hang``: no answer within the time limit; ``memory``: ``MemoryError`` under the limit;
- ``non-finite``: a NaN or infinity in what was read or printed, or a schedule past the time limit.
"""
from __future__ import annotations

import contextlib
import io
import json
import math
import multiprocessing
import os
import random
import re
import resource
import struct
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

GOOD = ("typed error", "load")
BAD = ("untyped", "hang", "memory", "non-finite")
OUTCOMES = GOOD + BAD

#: Longest schedule a fuzzed BML document or scene may produce, seconds (the parsers' own limit).
MAX_SCHEDULE_S = 24 * 3600.0

# -- seeds -----------------------------------------------------------------------------------------------------

TINY_BVH = """HIERARCHY
ROOT Hips
{
\tOFFSET 0.0 90.0 0.0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Spine
\t{
\t\tOFFSET 0.0 10.0 0.0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tJOINT Head
\t\t{
\t\t\tOFFSET 0.0 50.0 0.0
\t\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\t\tEnd Site
\t\t\t{
\t\t\t\tOFFSET 0.0 20.0 0.0
\t\t\t}
\t\t}
\t}
}
MOTION
Frames: 3
Frame Time: 0.0333333
0.0 90.0 0.0 0.0 0.0 0.0 0.0 5.0 0.0 0.0 0.0 0.0
1.0 90.5 0.0 10.0 0.0 0.0 0.0 6.0 0.0 0.0 2.0 0.0
2.0 91.0 0.0 20.0 0.0 0.0 0.0 7.0 0.0 0.0 4.0 0.0
"""

TINY_BML = """<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1" characterId="bob">
  <gaze id="g1" target="cup" start="0.2" end="2.0"/>
  <head id="h1" lexeme="NOD" start="g1:start+0.5" repetition="2"/>
  <speech id="s1" start="h1:end"><text>Hello <sync id="m1"/> there.</text></speech>
  <face id="f1" type="FACS" au="12" amount="0.5" start="s1:m1" end="s1:end"/>
  <constraint id="c1"><synchronize ref="h1:stroke"><sync ref="f1:start"/></synchronize></constraint>
</bml>
"""

TINY_SCENE_TOML = """fps = 30
duration = 3.0
seed = 4

[[character]]
name = "bob"
file = "bob.bvh"
position = [0.0, 0.0, 0.0]
facing = "ann"

[[character]]
name = "ann"
file = "bob.bvh"
position = [0.0, 0.0, 2.0]
facing = [0.0, 0.0]

[[object]]
name = "cup"
position = [0.4, 1.0, 1.6]
size = 0.1

[[block]]
at = 0.5
character = "bob"
bml = '<bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1"><head id="h1" lexeme="NOD"/></bml>'

[[block]]
at = 1.0
character = "ann"
file = "block.xml"
"""

TINY_SCENE_XML = """<scene fps="30" duration="3">
  <character name="bob" file="bob.bvh" position="0 0 0" facing="ann"/>
  <character name="ann" file="bob.bvh" position="0 0 2" facing="0"/>
  <object name="cup" position="0.4 1 1.6" size="0.1"/>
  <block at="0.5" character="bob"><bml xmlns="http://www.bml-initiative.org/bml/bml-1.0" id="b1"><head id="h1" lexeme="NOD"/></bml></block>
  <block at="1" character="ann" file="block.xml"/>
</scene>
"""


@dataclass(frozen=True)
class Seed:
    """A valid input: its label, the file's name and bytes, and the files beside it (name -> bytes)."""

    label: str
    name: str
    data: bytes
    beside: tuple = ()


@dataclass(frozen=True)
class Format:
    """A fuzzed format: ``kind`` is ``"file"`` (through ``infuse info``), ``"bml"`` or ``"scene"``;
    ``corpus`` the glob patterns of its seeds in the corpus and the wild set; ``text`` whether the
    text mutations apply."""

    name: str
    kind: str
    corpus: tuple = ()
    text: bool = True


FORMATS = {f.name: f for f in (
    Format("bvh", "file", ("**/*.bvh",)),
    Format("glb", "file", ("**/*.glb", "**/*.vrm"), text=False),
    Format("gltf", "file", ("**/*.gltf",)),
    Format("collada", "file", ("**/*.dae",)),
    Format("fbx", "file", ("**/*.fbx", "**/*.FBX"), text=False),
    Format("asf", "file", ("**/*.asf",)),
    Format("amc", "file", ("**/*.amc",)),
    Format("ogre", "file", ("**/*.skeleton.xml",)),
    Format("sk", "file", ("**/*.sk",)),
    Format("skm", "file", ("**/*.skm",)),
    Format("bml", "bml", ("bml/**/*.xml",)),
    Format("scene", "scene"),
)}


def built_seeds(fmt: str) -> list[Seed]:
    """Seeds made here or by the tests' own builders (no data files)."""
    if fmt == "bvh":
        return [Seed("tiny", "case.bvh", TINY_BVH.encode())]
    if fmt in ("glb", "gltf"):
        from gltf_builder import mini_rig

        builder, _ = mini_rig()
        if fmt == "glb":
            return [Seed("mini_rig", "case.glb", builder.glb())]
        with tempfile.TemporaryDirectory() as folder:
            path = builder.write_gltf(Path(folder) / "case.gltf", external=True)
            beside = (("case.bin", (Path(folder) / "case.bin").read_bytes()),)
            return [Seed("mini_rig", "case.gltf", path.read_bytes(), beside)]
    if fmt == "collada":
        from test_collada import SCENE

        return [Seed("synthetic", "case.dae", SCENE.encode())]
    if fmt == "ogre":
        from test_ogre import SKELETON

        return [Seed("synthetic", "case.skeleton.xml", SKELETON.encode())]
    if fmt == "fbx":
        from test_fbx import fbx_bytes, fbx_text, scene

        return [Seed("binary", "case.fbx", fbx_bytes(scene())), Seed("ascii", "case.fbx", fbx_text(scene()))]
    if fmt == "bml":
        return [Seed("tiny", "case.xml", TINY_BML.encode())]
    if fmt == "scene":
        beside = (("bob.bvh", TINY_BVH.encode()), ("block.xml", TINY_BML.encode()))
        return [Seed("toml", "case.toml", TINY_SCENE_TOML.encode(), beside),
                Seed("xml", "case.xml", TINY_SCENE_XML.encode(), beside)]
    return []


def _first_frames(amc: bytes, frames: int) -> bytes:
    """An AMC motion cut after its first ``frames`` frames (a frame starts with a line holding its number)."""
    lines = amc.splitlines(keepends=True)
    starts = [i for i, line in enumerate(lines) if line.strip().isdigit()]
    return b"".join(lines[:starts[frames]]) if len(starts) > frames else amc


def corpus_seeds(fmt: str, roots: list[Path], max_bytes: int) -> list[Seed]:
    """Seeds read in place from the corpus and wild folders: files up to ``max_bytes`` (longer motions
    cut to their first frames), with the files a reader needs beside them (the ``.asf`` of an ``.amc``)."""
    seeds = []
    for root in roots:
        for pattern in FORMATS[fmt].corpus:
            for path in sorted(root.glob(pattern)):
                if not path.is_file() or "labels" in path.parts:
                    continue
                data = path.read_bytes()
                if fmt == "amc" and len(data) > max_bytes:
                    data = _first_frames(data, 30)
                if len(data) > max_bytes:
                    continue
                beside = ()
                if fmt == "amc":
                    subject = path.parent / (path.stem.split("_")[0] + ".asf")
                    if not subject.is_file():
                        continue
                    beside = (("case.asf", subject.read_bytes()),)
                name = "case" + (".skeleton.xml" if fmt == "ogre" else path.suffix.lower())
                seeds.append(Seed(str(path.relative_to(root)), name, data, beside))
    return seeds


# -- mutations -------------------------------------------------------------------------------------------------

#: Values the number mutation puts in place of a number: limits, overflows, non-finite and odd spellings.
INTERESTING_NUMBERS = ("nan", "NaN", "inf", "-inf", "Infinity", "1e308", "-1e308", "1e309", "1e-320", "0", "-0", "-1",
                       "2147483647", "2147483648", "4294967295", "4294967296", "9223372036854775808", "100000000000000",
                       "1e15", "0x10", "1_000", "+5", "5e", ".", "")
#: Strings the JSON mutation puts in place of a string: escapes, devices, absolute paths, odd URIs.
INTERESTING_STRINGS = ("../outside.bin", "/dev/zero", "/dev/urandom", "/etc/passwd", "case.bin/../../x", "data:,",
                       "data:application/octet-stream;base64,!!!!", "file:///etc/hostname", "%2e%2e/x", "", "\u0000",
                       "\u202e", "a" * 5000, "LINEAR", "STEP", "CUBICSPLINE", "rotation", "weights", "VEC4", "MAT4")
#: 32-bit words the binary mutation writes: counts and lengths that ask for too much.
INTERESTING_WORDS = (0, 1, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 0x10000, 0x7FFFFFF0, 0xFFFFFFF0)

KINDS = ("truncate", "flip", "insert", "delete", "repeat", "number", "word", "binary", "json", "nest")
_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_WORD = re.compile(rb"[A-Za-z_][A-Za-z0-9_.:]*")
#: Largest mutated case, bytes (the issue's 10 MB documents).
MAX_CASE_BYTES = 10_000_000


def _at(data: bytes, where: float) -> int:
    return min(len(data), max(0, int(where * len(data))))


def _nth_match(pattern: re.Pattern, data: bytes, where: float, limit: int = 4000):
    matches = []
    for m in pattern.finditer(data):
        matches.append(m)
        if len(matches) >= limit:
            break
    return matches[min(len(matches) - 1, int(where * len(matches)))] if matches else None


def _json_mutation(doc, where: float, n: int):
    """``doc`` (parsed JSON) with one leaf, picked by ``where``, replaced by an interesting value."""
    leaves = []

    def visit(node, path):
        if len(leaves) > 5000:
            return
        if isinstance(node, dict):
            for k, v in node.items():
                visit(v, path + (k,))
        elif isinstance(node, list):
            for i, v in enumerate(node):
                visit(v, path + (i,))
        leaves.append(path)

    visit(doc, ())
    path = leaves[min(len(leaves) - 1, int(where * len(leaves)))]
    rng = random.Random(n)
    choice = rng.randrange(6)
    value = (rng.choice((float("nan"), float("inf"), 1e308, -1.0, 2 ** 31, 2 ** 32 - 1, 2 ** 63, 0, 10 ** 14, 3.5))
             if choice < 3 else rng.choice(INTERESTING_STRINGS) if choice < 5 else rng.choice(([], {}, None, True)))
    if not path:
        return value
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = value
    return doc


def _glb_json(data: bytes):
    """(json text, the bytes after the JSON chunk) of a GLB, or None."""
    if len(data) < 20 or data[:4] != b"glTF":
        return None
    length, kind = struct.unpack_from("<II", data, 12)
    if kind != 0x4E4F534A or 20 + length > len(data):
        return None
    return data[20:20 + length], data[20 + length:]


def _with_json(data: bytes, edit) -> bytes:
    """``data`` (JSON text or a GLB) with its JSON document passed through ``edit``; ``data`` when it has none."""
    glb = _glb_json(data)
    text = glb[0] if glb else data
    try:
        doc = json.loads(text)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return data
    out = json.dumps(edit(doc), allow_nan=True).encode()
    if not glb:
        return out
    out += b" " * ((-len(out)) % 4)
    chunks = struct.pack("<II", len(out), 0x4E4F534A) + out + glb[1]
    return b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks


def mutate(data: bytes, ops, max_bytes: int = MAX_CASE_BYTES) -> bytes:
    """``data`` after the operations ``ops``: a sequence of ``(kind, where, n)`` (see :data:`KINDS`), cut
    to ``max_bytes``."""
    for kind, where, n in ops:
        at = _at(data, where)
        rng = random.Random(n)
        if kind == "truncate":
            data = data[:at]
        elif kind == "flip" and data:
            i = min(at, len(data) - 1)
            data = data[:i] + bytes([data[i] ^ (1 << (n % 8))]) + data[i + 1:]
        elif kind == "insert":
            junk = rng.choice((bytes(rng.randrange(256) for _ in range(1 + n % 16)), b"{", b"}", b"<", b">", b"\n",
                               b"\x00", b"\xff\xfe", b" -", b"\"", b"<!--", b"]]>", b"&#0;"))
            data = data[:at] + junk + data[at:]
        elif kind == "delete":
            data = data[:at] + data[at + 1 + n % 64:]
        elif kind == "repeat" and data:
            span = data[at:at + 1 + n % 256] or data[-1:]
            times = rng.choice((2, 10, 1000, 5000, 100000))
            data = data[:at] + span * min(times, max_bytes // len(span)) + data[at:]
        elif kind == "number":
            m = _nth_match(_NUMBER, data, where)
            if m:
                data = data[:m.start()] + rng.choice(INTERESTING_NUMBERS).encode() + data[m.end():]
        elif kind == "word":
            m, other = _nth_match(_WORD, data, where), _nth_match(_WORD, data, rng.random())
            if m and other:
                data = data[:m.start()] + other.group() + data[m.end():]
        elif kind == "binary" and len(data) >= 4:
            i = min(at - at % 4, len(data) - 4)
            data = data[:i] + struct.pack("<I", rng.choice(INTERESTING_WORDS)) + data[i + 4:]
        elif kind == "json":
            data = _with_json(data, lambda doc: _json_mutation(doc, where, n))
        elif kind == "nest":
            data = _nest(data, at, rng)
        if len(data) > max_bytes:
            data = data[:max_bytes]
    return data


def _nest(data: bytes, at: int, rng: random.Random) -> bytes:
    """Deep nesting or long chains in the shape of the file: braces (BVH, SmartBody), elements (XML) or
    a chain of glTF nodes."""
    depth = rng.choice((100, 1000, 5000, 20000))
    glb = _glb_json(data)
    if glb or data.lstrip()[:1] == b"{":
        def chain(doc):
            nodes = doc.get("nodes") if isinstance(doc, dict) else None
            if not isinstance(nodes, list):
                return doc
            start = len(nodes)
            nodes.extend({"name": f"n{i}", "children": [start + i + 1]} for i in range(depth - 1))
            nodes.append({"name": "end"})
            if nodes[:start] and isinstance(nodes[0], dict):
                nodes[0].setdefault("children", []).append(start)
            return doc
        return _with_json(data, chain)
    if b"<" in data[:200]:
        open_tag = rng.choice((b"<node>", b"<a>", b"<bml>", b"<bone>", b"<sync>"))
        close_tag = b"</" + open_tag[1:]
        return data[:at] + open_tag * depth + close_tag * depth + data[at:]
    joint = rng.choice((b"JOINT j\n{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n",
                        b"{\n", b"(\n", b"joint j\n{\n"))
    return data[:at] + joint * depth + b"}\n" * depth + data[at:]


def random_ops(rng: random.Random, text: bool) -> list:
    """One to four random operations (the long run's draw); binary formats skip the text-only kinds."""
    kinds = KINDS if text else tuple(k for k in KINDS if k not in ("number", "word"))
    return [(rng.choice(kinds), rng.random(), rng.randrange(2 ** 32)) for _ in range(rng.randint(1, 4))]


# -- running one case ------------------------------------------------------------------------------------------

@dataclass
class Outcome:
    kind: str
    detail: str = ""


class _NonFinite(ValueError):
    pass


def _refuse_constant(name):
    raise _NonFinite(name)


def _float_arrays(asset):
    sk = asset.skeleton
    yield "skeleton", sk.rest_translations
    yield "skeleton", sk.rest_rotations
    yield "skeleton", sk.end_site_offsets
    for name, m in asset.motions.items():
        yield f"clip {name!r}", np.asarray([m.fps], dtype=float)
        yield f"clip {name!r}", m.local_rotations
        yield f"clip {name!r}", m.root_translations
        if m.joint_translations is not None:
            yield f"clip {name!r}", m.joint_translations
    for i, mesh in enumerate(asset.meshes):
        for key, value in vars(mesh).items():
            if isinstance(value, np.ndarray) and value.dtype.kind == "f":
                yield f"mesh {i} {key}", value


def _answer_lines(stderr: str) -> list[str]:
    return [ln for ln in stderr.splitlines() if ln.strip() and not ln.startswith("infuse: warning:")]


def _cli(argv: list[str]) -> tuple[int, str, str]:
    from infuse.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def _typed_answer(code: int, stderr: str, path: Path) -> Outcome:
    lines = _answer_lines(stderr)
    if code in (2, 3) and len(lines) == 1 and lines[0].startswith("infuse: error:") and path.name in lines[0]:
        return Outcome("typed error", lines[0])
    if "MemoryError" in stderr:
        return Outcome("memory", lines[-1] if lines else "")
    return Outcome("untyped", f"exit {code}: " + " | ".join(lines)[:500])


def _check_file(path: Path) -> Outcome:
    import infuse

    code, out, err = _cli(["info", "--json", str(path)])
    if code != 0:
        return _typed_answer(code, err, path)
    try:
        json.loads(out, parse_constant=_refuse_constant)
    except _NonFinite as exc:
        return Outcome("non-finite", f"info --json prints {exc}")
    asset = infuse.load(path)
    for place, array in _float_arrays(asset):
        if not np.all(np.isfinite(array)):
            return Outcome("non-finite", f"{place} read from the file")
    for ext in (".glb", ".bvh"):
        written = path.parent / f"roundtrip{ext}"
        infuse.save(asset, written)
        back = infuse.load(written)
        for place, array in _float_arrays(back):
            if not np.all(np.isfinite(array)):
                return Outcome("non-finite", f"{place} in the written {ext}")
    return Outcome("load")


def _check_bml(path: Path) -> Outcome:
    from infuse.bml import Scheduler, parse_bml_file
    from infuse.errors import InfuseError

    try:
        document = parse_bml_file(path)
    except InfuseError as exc:
        text = str(exc)
        ok = exc.exit_code in (2, 3) and "\n" not in text and path.name in text
        return Outcome("typed error" if ok else "untyped", text[:500])
    scheduler = Scheduler()
    records = scheduler.submit(document)
    scheduler.flush()
    return _schedule_outcome(records)


def _schedule_outcome(records) -> Outcome:
    for record in records:
        times = [record.start_s, record.end_s] + [t for a in record.activations for t in a.sync_times.values()]
        if not all(math.isfinite(t) for t in times):
            return Outcome("non-finite", f"block {record.block.id!r} schedule")
        if max(abs(t) for t in times) > MAX_SCHEDULE_S:
            return Outcome("non-finite", f"block {record.block.id!r} runs {max(times):.3g} s")
    return Outcome("load")


def _check_scene(path: Path) -> Outcome:
    from infuse.bml import Scheduler, parse_bml, parse_bml_file
    from infuse.errors import InfuseError
    from infuse.scene.scenefile import read_scene_file

    try:
        spec = read_scene_file(path)
        scheduler = Scheduler()
        records = []
        for block in spec.blocks:
            document = parse_bml_file(block.file) if block.file else parse_bml(block.bml, file=str(path))
            records += scheduler.submit(document, at=block.at, character=block.character)
        scheduler.flush()
    except InfuseError as exc:
        text = str(exc)
        ok = exc.exit_code in (2, 3) and "\n" not in text and (path.name in text or ".xml" in text)
        return Outcome("typed error" if ok else "untyped", text[:500])
    for number in [spec.fps, spec.duration or 0.0] + [b.at for b in spec.blocks]:
        if not math.isfinite(number) or abs(number) > MAX_SCHEDULE_S:
            return Outcome("non-finite", f"scene number {number}")
    return _schedule_outcome(records)


def run_case(fmt: str, name: str, data: bytes, beside, folder: Path) -> Outcome:
    """Write the case into ``folder`` and classify what infuse makes of it (in this process)."""
    for old in folder.iterdir():
        old.unlink()
    for other, content in beside:
        (folder / other).write_bytes(content)
    path = folder / name
    path.write_bytes(data)
    kind = FORMATS[fmt].kind
    from infuse.errors import InfuseError

    try:
        if kind == "file":
            return _check_file(path)
        if kind == "bml":
            return _check_bml(path)
        return _check_scene(path)
    except InfuseError as exc:  # raised past the reader: decoding the meshes, writing, reading back
        return _typed_answer(exc.exit_code, f"infuse: error: {exc}", path)
    except MemoryError:
        return Outcome("memory", "MemoryError")
    except RecursionError:
        return Outcome("untyped", "RecursionError")
    except Exception as exc:  # the fuzzer's finding: a bug, reported with where it was raised
        where = traceback.extract_tb(exc.__traceback__)[-1]
        return Outcome("untyped", f"{type(exc).__name__}: {str(exc)[:200]} at {Path(where.filename).name}:{where.lineno}")


# -- the worker process ----------------------------------------------------------------------------------------

def _cpu_seconds(pid: int) -> float:
    """User and system CPU seconds of process ``pid`` so far (0 once it is gone)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _vm_bytes() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024
    return 0


def _serve(conn, memory_bytes: int, paths: list[str]) -> None:
    import sys

    sys.path[:0] = [p for p in paths if p not in sys.path]
    import infuse.cli  # noqa: F401  (imported before the limit: the plugins' own start-up is not the case's)
    from infuse import registry

    registry.readers(), registry.writers(), registry.commands()
    with tempfile.TemporaryDirectory(prefix="infuse-fuzz-warm-") as folder:  # lazy imports happen here, not in a case
        for fmt in ("bvh", "glb", "bml", "scene"):
            for seed in built_seeds(fmt):
                run_case(fmt, seed.name, seed.data, seed.beside, Path(folder))
    if memory_bytes:
        limit = _vm_bytes() + memory_bytes
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    conn.send("ready")
    with tempfile.TemporaryDirectory(prefix="infuse-fuzz-") as folder:
        while True:
            try:
                job = conn.recv()
            except EOFError:
                return
            if job is None:
                return
            outcome = run_case(*job, Path(folder))
            conn.send((outcome.kind, outcome.detail))


@dataclass
class Worker:
    """A child process that runs cases one at a time, each given ``timeout_s`` seconds and
    ``memory_bytes`` of address space beyond what the child had after start-up; a hung child is
    killed and replaced."""

    timeout_s: float = 20.0
    memory_bytes: int = 1 << 30
    _process: object = field(default=None, repr=False)
    _conn: object = field(default=None, repr=False)

    def _start(self):
        import sys

        context = multiprocessing.get_context("spawn")
        parent, child = context.Pipe()
        tests = str(Path(__file__).resolve().parent)
        self._process = context.Process(target=_serve, args=(child, self.memory_bytes, [tests] + sys.path), daemon=True)
        # One thread per library and few malloc arenas in the child: a thread pool started lazily inside
        # a case would count its stacks and arenas against the case's memory limit.
        settings = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "MALLOC_ARENA_MAX": "2"}
        saved = {name: os.environ.get(name) for name in settings}
        os.environ.update(settings)
        try:
            self._process.start()
        finally:
            for name, value in saved.items():
                if value is None:
                    os.environ.pop(name)
                else:
                    os.environ[name] = value
        child.close()
        self._conn = parent
        # Start-up (imports, a warm-up case per kind) is not a case's time; a loaded machine may take long.
        if not parent.poll(600) or parent.recv() != "ready":
            self.close(kill=True)
            raise RuntimeError("the fuzz worker did not start")

    def run(self, fmt: str, seed: Seed, data: bytes) -> Outcome:
        if self._process is None or not self._process.is_alive():
            self._start()
        self._conn.send((fmt, seed.name, data, seed.beside))
        # A hang is a case that spends timeout_s of CPU time (the machine may be shared, so wall time
        # alone would count waiting as hanging), or five times that in wall time.
        started_cpu, started = _cpu_seconds(self._process.pid), time.monotonic()
        while True:
            if self._conn.poll(min(1.0, self.timeout_s)):
                try:
                    kind, detail = self._conn.recv()
                    return Outcome(kind, detail)
                except (EOFError, OSError):
                    break
            if not self._process.is_alive():
                break
            cpu = _cpu_seconds(self._process.pid) - started_cpu
            if cpu > self.timeout_s or time.monotonic() - started > 5 * self.timeout_s:
                break
        died = self._process.exitcode
        self.close(kill=True)
        if died is not None:
            return Outcome("memory" if died in (-9, -6) else "untyped", f"worker died with code {died}")
        return Outcome("hang", f"no answer after {self.timeout_s:g} s of CPU time")

    def close(self, kill: bool = False) -> None:
        if self._process is None:
            return
        if not kill and self._process.is_alive():
            try:
                self._conn.send(None)
                self._process.join(5)
            except (BrokenPipeError, OSError):
                pass
        if self._process.is_alive():
            self._process.kill()
            self._process.join(5)
        self._process = self._conn = None
