"""``infuse speak CHARACTER "text" -o out.glb``: speech, lip sync and the files that go with them.

Writes ``out.glb`` (the character with one clip, ``speech``: morph-weight tracks on its own face
channels, or face-joint rotations for joint faces, over a living idle of the body, see
:mod:`.body`, unless ``--face-only``; standing on the ground unless ``--no-ground``), ``out.wav``
next to it and ``out.timeline.json`` (phonemes, visemes, words, marks, the channels driven).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from infuse import fileio
from infuse.atomic import atomic_path
from infuse.cli.builtin import add_read_options, read_options
from infuse.errors import InputError, UnusableInputError, UsageError
from infuse.grounding import on_ground
from infuse.mapping import map_skeleton
from infuse.speech import tts_engine

from .body import IDLE_PACK, idle_body, with_face
from .channels import detect_face
from .expressions import Expression
from .lipsync import LipSyncSettings, choose_viseme_set, lipsync
from .tables import VISEME_SETS

#: Outputs whose writer takes morph-weight tracks.
MORPH_TRACK_SUFFIXES = (".glb", ".gltf", ".vrm")


def add_arguments(p) -> None:
    p.add_argument("character", help="the character file (glTF/VRM, FBX, SmartBody .sk, ...)")
    p.add_argument("text", nargs="?", default=None,
                   help='what to say; sync marks allowed: <sync id="x"/> (optional with --tts file)')
    p.add_argument("-o", "--output", required=True, help="the animation to write (e.g. out.glb); the WAV and the "
                                                         "timeline go next to it")
    p.add_argument("--tts", default="espeak", help="TTS engine: espeak (default) or file (a recording)")
    p.add_argument("--voice", default=None, help="espeak-ng voice (default en)")
    p.add_argument("--rate", type=int, default=None, help="words per minute (espeak-ng, 80..450)")
    p.add_argument("--audio", help="the recording (--tts file)")
    p.add_argument("--timing", help="its phoneme timing file: TextGrid, MFA JSON, JSON or TSV (--tts file)")
    p.add_argument("--fps", type=float, default=30.0, help="animation frame rate (default 30)")
    p.add_argument("--viseme-set", choices=VISEME_SETS, help="which of the character's viseme sets to drive")
    p.add_argument("--map", help="a map file whose \"face\" entry declares the face channels")
    p.add_argument("--expression", action="append", default=[], metavar="NAME[:INTENSITY]",
                   help="hold a facial expression during the speech: smile, frown, surprise, raised_brows, blink, "
                        "sad, angry, or an action unit such as AU12 (repeatable)")
    p.add_argument("--clip", default="speech", help="clip name (default speech)")
    p.add_argument("--face-only", action="store_true",
                   help="move the face only (default: the body idles too: breathing, blinks, saccades, nods)")
    p.add_argument("--idle-pack", default=IDLE_PACK, metavar="PACK",
                   help=f"behaviour pack whose idle clip the body stands in (default {IDLE_PACK}, when installed)")
    p.add_argument("--no-ground", dest="ground", action="store_false",
                   help="keep the character's own height (default: its feet's lowest point at y = 0)")
    add_read_options(p)


def _expression(spec: str) -> Expression:
    name, _, level = spec.partition(":")
    try:
        intensity = float(level) if level else 1.0
    except ValueError:
        raise UsageError(f"--expression {spec!r}: intensity must be a number") from None
    if not 0.0 <= intensity <= 1.0:
        raise UsageError(f"--expression {spec!r}: intensity must be within 0..1")
    return Expression(name, intensity)


def _engine(args):
    if args.tts == "file":
        if not args.audio or not args.timing:
            raise UsageError("--tts file needs --audio and --timing")
        return tts_engine("file", audio=args.audio, timing=args.timing)
    settings = {k: v for k, v in (("voice", args.voice), ("rate", args.rate)) if v is not None}
    return tts_engine(args.tts, **settings)


def _on_ground(asset, motion, map_file):
    """``motion`` standing on the ground (see :mod:`infuse.grounding`); as it is for a character
    that is not a humanoid (no feet to stand on)."""
    try:
        mapping = map_skeleton(asset, saved_map=map_file)
    except UnusableInputError:
        return motion
    return on_ground(asset, mapping, motion)


def run(args) -> int:
    out = Path(args.output)
    if out.suffix.lower() in (".wav", ".json"):
        raise UsageError(f"-o names the animation (e.g. out.glb), not {out.suffix}")
    if args.text is None and args.tts != "file":
        raise InputError(None, "text", "empty text: nothing to say")
    expressions = [_expression(e) for e in args.expression]
    asset = fileio.load(args.character, format=args.read_format, **read_options(args))
    face = detect_face(asset, args.map)
    set_name = choose_viseme_set(face, args.viseme_set)  # before any file is written: fail early on a faceless character
    if set_name != "jaw" and face.kinds.get(set_name) == "morph" and out.suffix.lower() not in MORPH_TRACK_SUFFIXES:
        raise UsageError(f"this character speaks with morph targets, which only glTF can carry: write "
                         f"{', '.join(MORPH_TRACK_SUFFIXES)}, not {out.suffix or 'a file without extension'}")
    engine = _engine(args)
    wav = out.with_suffix(".wav")
    timeline_path = out.with_name(out.stem + ".timeline.json")
    with atomic_path(wav) as wav_tmp:  # the WAV appears only once the animation is written too
        utterance = engine.synthesize(args.text, wav_tmp)
        result = lipsync(utterance, face, args.viseme_set, LipSyncSettings(fps=args.fps), asset.skeleton, expressions)
        face_motion = result.motion(asset.skeleton, args.clip)
        idle, body = (None, "face only") if args.face_only else idle_body(
            asset, len(result.times), args.fps, utterance.words, args.idle_pack, args.map, clip=args.clip, ground=args.ground)
        if idle is None:
            motion = face_motion
            if motion is not None and args.ground and motion.animated_mask.any():
                motion = _on_ground(asset, motion, args.map)
        else:
            motion = with_face(idle.motions[args.clip], face_motion)
        asset.motions = {args.clip: motion} if motion is not None else {}
        fileio.save(asset, out)
        doc = dict(result.timeline, wav=wav.name, animation=out.name, clip=args.clip,
                   character=str(args.character), joints=sorted(result.joint_rotations))
        with atomic_path(timeline_path) as tmp:
            tmp.write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")

    driven = (f"{len(result.morph_weights)} morph targets" if result.morph_weights
              else f"{len(result.joint_rotations)} face joints")
    print(f"wrote {out}: clip {args.clip!r}, {len(result.times)} frames at {args.fps:g} fps, viseme set "
          f"{result.viseme_set} ({driven}); body: {body}")
    print(f"wrote {wav}: {utterance.duration_s:.2f} s ({utterance.engine})")
    print(f"wrote {timeline_path}: {len(utterance.phonemes)} phonemes, {len(utterance.words)} words, {len(utterance.marks)} marks")
    sys.stdout.flush()
    return 0
