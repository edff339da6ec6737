"""``<speech>``: text with inline marks, timed by the TTS engine when one is given, else estimated."""
from __future__ import annotations

from infuse.bml import BehaviourPlan, TimingModel

ATTRIBUTES = {"type", "language", "voice", "text", "ref", "policy"}
# Speech has no preparation or retraction: its ready-like points are its start, its relax-like points its end.
_ALIASES = {"ready": "start", "strokeStart": "start", "strokeEnd": "end", "relax": "end"}


def plan(behaviour, context) -> BehaviourPlan:
    text = behaviour.text if behaviour.text is not None else (behaviour.attribute("text") or "").strip()
    marks = [(m, o) for m, o in behaviour.marks if m not in ("start", "end")]
    timing = context.speech_timer.time_speech(text, marks, voice=behaviour.attribute("voice"),
                                              language=behaviour.attribute("language"))
    points = {"start": 0.0, **{m: timing.mark_times_s[m] for m, _ in marks}, "end": timing.duration_s}
    parameters = {"text": text, "marks_s": {m: timing.mark_times_s[m] for m, _ in marks},
                  "duration_s": timing.duration_s, "timing_source": timing.source,
                  "voice": behaviour.attribute("voice"), "language": behaviour.attribute("language"),
                  "audio_ref": behaviour.attribute("ref"), **({"tts": timing.details} if timing.details else {})}
    notes = () if text else ("the speech has no text",)
    return BehaviourPlan(TimingModel.from_points(points, stretchable=False, aliases=_ALIASES), "speech", parameters,
                         notes=notes)
