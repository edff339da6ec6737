"""ctypes binding to libespeak-ng: synthesis that returns the audio and its events.

Struct layouts follow ``speak_lib.h`` (API revision 12)::

    typedef struct {
        espeak_EVENT_TYPE type; unsigned int unique_identifier; int text_position; int length;
        int audio_position;  /* ms */  int sample;  void *user_data;
        union { int number; const char *name; char string[8]; } id;
    } espeak_EVENT;
    typedef int (t_espeak_callback)(short *wav, int numsamples, espeak_EVENT *events);

The library is initialised once per process (libespeak-ng keeps global state) in synchronous
retrieval mode with phoneme events on; every synthesis sets its own callback, voice and parameters
under a lock. ``Event.sample`` is the sample index in the audio at which the event happens.

This module needs only the standard library, so a child process that synthesizes starts fast;
its errors are :class:`EspeakError` subclasses, which the engine turns into infuse errors.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import os
import threading
from ctypes import CFUNCTYPE, POINTER, Structure, Union, c_char, c_char_p, c_int, c_short, c_uint, c_void_p
from array import array
from dataclasses import dataclass

#: Environment variable naming the libespeak-ng shared library (a file name or a path).
LIBRARY_ENV = "INFUSE_ESPEAK_LIBRARY"
DEFAULT_LIBRARY = "libespeak-ng.so.1"
INSTALL_HINT = "install it with: apt-get install espeak-ng libespeak-ng1"

# speak_lib.h constants
AUDIO_OUTPUT_SYNCHRONOUS = 2
INITIALIZE_PHONEME_EVENTS = 0x0001
INITIALIZE_DONT_EXIT = 0x8000
CHARS_UTF8 = 1
SSML = 0x10
ENDPAUSE = 0x1000
POS_CHARACTER = 1
PARAM_RATE, PARAM_VOLUME = 1, 2
RATE_MINIMUM, RATE_MAXIMUM = 80, 450
EVENT_KINDS = {0: "list_terminated", 1: "word", 2: "sentence", 3: "mark", 4: "play", 5: "end",
               6: "msg_terminated", 7: "phoneme", 8: "samplerate"}


class EspeakError(Exception):
    """A libespeak-ng problem; ``place`` names the setting at fault, if any."""

    place: str | None = None


class LibraryMissing(EspeakError):
    """libespeak-ng or its voice data cannot be loaded."""


class BadSetting(EspeakError):
    """A voice or parameter libespeak-ng does not accept."""

    def __init__(self, place: str, problem: str):
        super().__init__(problem)
        self.place = place


class _EventId(Union):
    _fields_ = [("number", c_int), ("name", c_char_p), ("string", c_char * 8)]


class _Event(Structure):
    _fields_ = [("type", c_int), ("unique_identifier", c_uint), ("text_position", c_int), ("length", c_int),
                ("audio_position", c_int), ("sample", c_int), ("user_data", c_void_p), ("id", _EventId)]


_SynthCallback = CFUNCTYPE(c_int, POINTER(c_short), c_int, POINTER(_Event))


@dataclass(frozen=True)
class Event:
    """One libespeak-ng event: ``kind`` ("phoneme", "word", "sentence", "mark", "end"), the sample index
    and millisecond position in the audio, the 1-based character position and length in the text
    (words), and ``name`` (phoneme mnemonic or mark name)."""

    kind: str
    sample: int
    audio_ms: int
    text_position: int
    length: int
    name: str = ""


@dataclass
class Synthesis:
    """Audio (mono 16-bit ``samples``, native byte order, at ``sample_rate`` Hz) and the events that came
    with it, in order."""

    samples: array
    sample_rate: int
    events: list[Event]


def library_path(setting: str | None = None) -> str:
    """The library to load: ``setting``, else ``$INFUSE_ESPEAK_LIBRARY``, else the system's libespeak-ng."""
    if setting:
        return str(setting)
    if os.environ.get(LIBRARY_ENV):
        return os.environ[LIBRARY_ENV]
    return ctypes.util.find_library("espeak-ng") or DEFAULT_LIBRARY


class Espeak:
    """One loaded libespeak-ng. Use :func:`espeak` to get the process-wide instance for a path."""

    def __init__(self, path: str):
        try:
            lib = ctypes.CDLL(path)
        except OSError as exc:
            raise LibraryMissing(f"espeak-ng library {path!r} could not be loaded ({exc}); {INSTALL_HINT}") from None
        try:
            lib.espeak_Initialize.argtypes = [c_int, c_int, c_char_p, c_int]
            lib.espeak_Initialize.restype = c_int
            lib.espeak_SetSynthCallback.argtypes = [_SynthCallback]
            lib.espeak_SetSynthCallback.restype = None
            lib.espeak_SetVoiceByName.argtypes = [c_char_p]
            lib.espeak_SetVoiceByName.restype = c_int
            lib.espeak_SetParameter.argtypes = [c_int, c_int, c_int]
            lib.espeak_SetParameter.restype = c_int
            lib.espeak_Synth.argtypes = [c_void_p, ctypes.c_size_t, c_uint, c_int, c_uint, c_uint, POINTER(c_uint), c_void_p]
            lib.espeak_Synth.restype = c_int
            lib.espeak_Synchronize.restype = c_int
        except AttributeError as exc:
            raise LibraryMissing(f"{path!r} is not libespeak-ng ({exc}); {INSTALL_HINT}") from None
        rate = lib.espeak_Initialize(AUDIO_OUTPUT_SYNCHRONOUS, 200, None, INITIALIZE_PHONEME_EVENTS | INITIALIZE_DONT_EXIT)
        if rate <= 0:
            raise LibraryMissing(f"espeak-ng found no voice data (espeak_Initialize returned {rate}); {INSTALL_HINT}")
        self.path = path
        self.sample_rate = int(rate)
        self._lib = lib
        self._lock = threading.Lock()
        self.fresh = True  # nothing synthesized yet: the next synthesis starts from the initial state

    def claim_fresh(self) -> bool:
        """True (once) when nothing has been synthesized in this process yet: the caller's next synthesis
        starts from the same state as a new process's would."""
        with self._lock:
            fresh, self.fresh = self.fresh, False
            return fresh

    def synthesize(self, text: str, voice: str = "en", rate: int = 175, volume: int = 100, ssml: bool = False) -> Synthesis:
        """Synthesize ``text`` (UTF-8; SSML marks when ``ssml``) with a sentence pause at the end.

        ``rate`` in words per minute (80..450), ``volume`` 0..200 (100 normal). Raises
        :class:`BadSetting` for an unknown voice or a rate out of range.
        """
        if not RATE_MINIMUM <= int(rate) <= RATE_MAXIMUM:
            raise BadSetting("rate", f"speech rate {rate} words/min is outside {RATE_MINIMUM}..{RATE_MAXIMUM}")
        samples = array("h")
        events: list[Event] = []

        def on_synth(wav, count, raw_events):
            if count > 0 and wav:
                samples.frombytes(ctypes.string_at(wav, count * 2))
            i = 0
            while raw_events[i].type != 0:
                e = raw_events[i]
                kind = EVENT_KINDS.get(e.type, str(e.type))
                if kind == "phoneme":
                    name = e.id.string.decode("utf-8", "replace")
                elif kind in ("mark", "play"):
                    name = e.id.name.decode("utf-8", "replace") if e.id.name else ""
                else:
                    name = ""
                if kind in ("phoneme", "word", "sentence", "mark", "end"):
                    events.append(Event(kind, int(e.sample), int(e.audio_position), int(e.text_position), int(e.length), name))
                i += 1
            return 0

        callback = _SynthCallback(on_synth)
        data = text.encode("utf-8")
        flags = CHARS_UTF8 | ENDPAUSE | (SSML if ssml else 0)
        with self._lock:
            lib = self._lib
            lib.espeak_SetSynthCallback(callback)
            if lib.espeak_SetVoiceByName(voice.encode("utf-8")) != 0:
                raise BadSetting("voice", f"unknown espeak-ng voice {voice!r} (list them with: espeak-ng --voices)")
            lib.espeak_SetParameter(PARAM_RATE, int(rate), 0)
            lib.espeak_SetParameter(PARAM_VOLUME, int(volume), 0)
            status = lib.espeak_Synth(data, len(data) + 1, 0, POS_CHARACTER, 0, flags, None, None)
            lib.espeak_Synchronize()
            self.fresh = False
        if status != 0:
            raise EspeakError(f"espeak-ng refused the text (espeak_Synth returned {status})")
        return Synthesis(samples, self.sample_rate, events)


_loaded: dict[str, Espeak] = {}
_loading = threading.Lock()


def espeak(path: str | None = None) -> Espeak:
    """The process-wide :class:`Espeak` for ``library_path(path)``; :class:`LibraryMissing` when absent."""
    resolved = library_path(path)
    with _loading:
        if resolved not in _loaded:
            _loaded[resolved] = Espeak(resolved)
        return _loaded[resolved]
