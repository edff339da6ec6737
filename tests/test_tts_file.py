"""The file TTS engine: a recording plus a phoneme timing file (TextGrid, MFA JSON, JSON, TSV, HTK)."""
from __future__ import annotations

import json
import wave

import numpy as np
import pytest

from infuse.errors import InputError, UsageError
from infuse.speech import SILENCE, tts_engine

RATE = 16000
# "hello world" as a forced aligner would time it (seconds), ARPAbet with stress and IPA labels
ALIGNED = [(0.10, 0.16, "HH", "h"), (0.16, 0.22, "AH0", "ə"), (0.22, 0.30, "L", "l"), (0.30, 0.45, "OW1", "oʊ"),
           (0.45, 0.52, "W", "w"), (0.52, 0.66, "ER1", "ɝ"), (0.66, 0.72, "L", "ɫ"), (0.72, 0.80, "D", "d")]
COMMON = ["hh", "ah", "l", "ow", "w", "er", "l", "d"]
WORDS = [(0.10, 0.45, "hello"), (0.45, 0.80, "world")]
DURATION = 1.0


@pytest.fixture()
def wav(tmp_path):
    path = tmp_path / "voice.wav"
    t = np.arange(int(DURATION * RATE)) / RATE
    tone = (3000 * np.sin(2 * np.pi * 180 * t) * ((t > 0.1) & (t < 0.8))).astype("<i2")
    with wave.open(str(path), "wb") as f:
        f.setnchannels(1)
        f.setsampwidth(2)
        f.setframerate(RATE)
        f.writeframes(tone.tobytes())
    return path


def _textgrid_long(phones, words, xmax=DURATION, marks=()):
    def tier(name, entries, index):
        rows = [f'    item [{index}]:', '        class = "IntervalTier"', f'        name = "{name}"',
                '        xmin = 0', f'        xmax = {xmax}', f'        intervals: size = {len(entries)}']
        for i, (s, e, label) in enumerate(entries, 1):
            rows += [f'        intervals [{i}]:', f'            xmin = {s}', f'            xmax = {e}', f'            text = "{label}"']
        return rows
    tiers = [tier("words", words, 1), tier("phones", phones, 2)]
    if marks:
        rows = ['    item [3]:', '        class = "TextTier"', '        name = "marks"', '        xmin = 0', f'        xmax = {xmax}',
                f'        points: size = {len(marks)}']
        for i, (t, name) in enumerate(marks, 1):
            rows += [f'        points [{i}]:', f'            number = {t}', f'            mark = "{name}"']
        tiers.append(rows)
    head = ['File type = "ooTextFile"', 'Object class = "TextGrid"', '', 'xmin = 0', f'xmax = {xmax}', 'tiers? <exists>',
            f'size = {len(tiers)}', 'item []:']
    return "\n".join(head + [r for t in tiers for r in t]) + "\n"


def _textgrid_short(phones, xmax=DURATION):
    lines = ['File type = "ooTextFile"', 'Object class = "TextGrid"', '', "0", str(xmax), "<exists>", "1",
             '"IntervalTier"', '"speaker1 - phones"', "0", str(xmax), str(len(phones))]
    for s, e, label in phones:
        lines += [str(s), str(e), f'"{label}"']
    return "\n".join(lines) + "\n"


def _with_silences(entries):
    """Fill gaps with empty labels, as MFA writes them."""
    out, t = [], 0.0
    for s, e, label in entries:
        if s > t:
            out.append((t, s, ""))
        out.append((s, e, label))
        t = e
    if t < DURATION:
        out.append((t, DURATION, ""))
    return out


def _spoken(utterance):
    return [p for _, _, p in utterance.phonemes if p != SILENCE]


def _check(utterance):
    assert _spoken(utterance) == COMMON
    assert utterance.duration_s == pytest.approx(DURATION)
    starts = [s for s, _, p in utterance.phonemes if p != SILENCE]
    np.testing.assert_allclose(starts, [a[0] for a in ALIGNED])
    assert utterance.phonemes[0][::2] == (0.0, SILENCE) and utterance.phonemes[0][1] == pytest.approx(0.10)
    assert utterance.phonemes[-1][1] == pytest.approx(DURATION)


def test_long_textgrid_arpabet_with_words_and_marks(wav, tmp_path):
    path = tmp_path / "voice.TextGrid"
    path.write_text(_textgrid_long(_with_silences([(s, e, a) for s, e, a, _ in ALIGNED]), _with_silences(WORDS),
                                   marks=[(0.45, "stroke")]))
    utterance = tts_engine("file", audio=wav, timing=path).synthesize()
    _check(utterance)
    assert utterance.meta["alphabet"] == "arpabet"
    assert [w for *_, w in utterance.words] == ["hello", "world"]
    assert utterance.marks == {"stroke": 0.45}
    assert utterance.text == "hello world"


def test_short_textgrid_ipa_utf16(wav, tmp_path):
    path = tmp_path / "voice.TextGrid"
    path.write_bytes(_textgrid_short(_with_silences([(s, e, i) for s, e, _, i in ALIGNED])).encode("utf-16"))
    utterance = tts_engine("file", audio=wav, timing=path).synthesize()
    _check(utterance)
    assert utterance.meta["alphabet"] == "ipa"
    assert utterance.source_phonemes[1:3] == ["h", "ə"]


def test_mfa_json_and_sync_marks_in_the_text(wav, tmp_path):
    path = tmp_path / "voice.json"
    doc = {"start": 0, "end": DURATION, "tiers": {
        "words": {"type": "interval", "entries": [list(w) for w in WORDS]},
        "phones": {"type": "interval", "entries": [[s, e, i] for s, e, _, i in ALIGNED]}}}
    path.write_text(json.dumps(doc, ensure_ascii=False))
    utterance = tts_engine("file", audio=wav, timing=path).synthesize('<sync id="start"/>hello <sync id="w"/>world<sync id="end"/>')
    _check(utterance)
    assert utterance.marks == {"start": 0.10, "w": 0.45, "end": 0.80}


def test_infuse_json_tsv_and_htk(wav, tmp_path):
    own = tmp_path / "own.json"
    own.write_text(json.dumps({"alphabet": "arpabet", "phonemes": [{"start": s, "end": e, "phoneme": a} for s, e, a, _ in ALIGNED],
                               "marks": {"m": 0.3}}))
    tsv = tmp_path / "voice.tsv"
    tsv.write_text("start\tend\tphone\n" + "".join(f"{s}\t{e}\t{a}\n" for s, e, a, _ in ALIGNED))
    lab = tmp_path / "voice.lab"
    lab.write_text("".join(f"{round(s * 1e7)} {round(e * 1e7)} {a.lower()}\n" for s, e, a, _ in ALIGNED))
    for path in (own, tsv, lab):
        utterance = tts_engine("file", audio=wav, timing=path).synthesize()
        _check(utterance)
    assert tts_engine("file", audio=wav, timing=own).synthesize().marks == {"m": 0.3}


def test_round_trip_of_an_utterance_document(wav, tmp_path):
    first = tts_engine("file", audio=wav, timing=_write(tmp_path / "a.tsv", ALIGNED)).synthesize()
    doc = tmp_path / "timeline.json"
    doc.write_text(json.dumps(first.to_dict()))
    again = tts_engine("file", audio=wav, timing=doc, alphabet="arpabet").synthesize(wav_path=tmp_path / "copy.wav")
    assert again.phonemes == first.phonemes
    assert (tmp_path / "copy.wav").read_bytes() == wav.read_bytes()


def _write(path, rows):
    path.write_text("".join(f"{s}\t{e}\t{a}\n" for s, e, a, *_ in rows))
    return path


@pytest.mark.parametrize("rows, match", [
    ([(0.1, 0.2, "AA1"), (0.15, 0.3, "B")], "overlaps the previous"),
    ([(0.3, 0.2, "AA1")], "before it starts"),
    ([(-0.1, 0.2, "AA1")], "before 0 s"),
    ([(0.1, 1.5, "AA1")], "after the end of the audio"),
    ([(0.1, 0.2, "XQ")], "unknown arpabet phoneme 'XQ'"),
    ([(0.1, 0.2, "sil")], "no spoken phoneme"),
])
def test_bad_timings_are_clear_errors(wav, tmp_path, rows, match):
    path = _write(tmp_path / "bad.tsv", rows)
    with pytest.raises(InputError, match=match) as info:
        tts_engine("file", audio=wav, timing=path, alphabet="arpabet").synthesize()
    assert "bad.tsv" in str(info.value)


@pytest.mark.parametrize("content, match", [
    ('File type = "ooTextFile"\nObject class = "TextGrid"\n0\n1\n<exists>\n1\n"IntervalTier"\n"words"\n0\n1\n1\n0\n1\n"hi"\n', "no phone tier"),
    ('File type = "ooTextFile"\nObject class = "TextGrid"\n0\n1\n<exists>\n1\n"IntervalTier"\n"phones"\n0\n1\n3\n0\n', "ends early"),
    ('File type = "ooTextFile"\nObject class = "Pitch"\n', "not a TextGrid"),
])
def test_bad_textgrids_are_clear_errors(wav, tmp_path, content, match):
    path = tmp_path / "bad.TextGrid"
    path.write_text(content)
    with pytest.raises(InputError, match=match):
        tts_engine("file", audio=wav, timing=path).synthesize()


def test_bad_json_table_and_audio(wav, tmp_path):
    broken = tmp_path / "broken.json"
    broken.write_text('{"phonemes": [[0.1, "x"]]}')
    with pytest.raises(InputError, match=r"phonemes\[0\]"):
        tts_engine("file", audio=wav, timing=broken).synthesize()
    table = tmp_path / "t.tsv"
    table.write_text("0.1\t0.2\tAA\n0.2\tx\tB\n")
    with pytest.raises(InputError, match="line 2"):
        tts_engine("file", audio=wav, timing=table).synthesize()
    not_wav = tmp_path / "voice.wav.txt"
    not_wav.write_text("hello")
    with pytest.raises(InputError, match="not a PCM WAV"):
        tts_engine("file", audio=not_wav, timing=_write(tmp_path / "ok.tsv", ALIGNED)).synthesize()
    with pytest.raises(InputError, match="file not found"):
        tts_engine("file", audio=tmp_path / "none.wav", timing=table).synthesize()
    with pytest.raises(UsageError, match="needs audio"):
        tts_engine("file").synthesize()
    with pytest.raises(InputError, match="need a words tier"):
        tts_engine("file", audio=wav, timing=_write(tmp_path / "ok.tsv", ALIGNED)).synthesize('<sync id="a"/>hello')
