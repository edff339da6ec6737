"""Lip sync without characters: tables, coarticulation, holds, timing against real espeak-ng speech."""
from __future__ import annotations


import numpy as np
import pytest

from infuse.errors import UsageError
from infuse.speech import SILENCE, Utterance, common_phonemes, tts_engine
from infuse_lipsync import coarticulation as co
from infuse_lipsync.expressions import action_units
from infuse_lipsync.lipsync import LipSyncSettings, lipsync, viseme_curves
from infuse_lipsync.tables import VISEME_SETS, phoneme_viseme, viseme_set

from espeak_support import require_espeak

# SmartBody's 15-viseme phoneme table (FaceFX style), as SmartBody documents it; "hh" has no shape of
# its own here (it takes its neighbours'), so it is left out.
SMARTBODY_TABLE = {
    "iy": "EE", "ih": "Ih", "eh": "Ih", "ey": "Ih", "ae": "Ih", "aw": "Ih", "ay": "Ih", "ah": "Ih",
    "aa": "Ao", "ao": "Ao", "oy": "oh", "ow": "oh", "uh": "oh", "uw": "oh", "er": "Er", "s": "Z", "z": "Z",
    "sh": "j", "zh": "j", "jh": "j", "ch": "j", "f": "F", "v": "F", "th": "Th", "dh": "Th", "m": "BMP", "b": "BMP",
    "p": "BMP", "n": "NG", "ng": "NG", "l": "D", "d": "D", "t": "D", "r": "R", "w": "OO", "y": "OO", "g": "KG", "k": "KG",
}


def test_every_phoneme_has_a_target_in_every_set():
    for name in VISEME_SETS:
        vs = viseme_set(name)
        assert set(vs.phonemes) == set(common_phonemes())
        assert vs.targets.shape == (len(vs.phonemes), len(vs.channels))
        assert np.all((vs.targets >= 0) & (vs.targets <= 1))
        spoken = [i for i, p in enumerate(vs.phonemes) if phoneme_viseme(p) not in ("", "sil", "PP")]
        # every spoken non-bilabial phoneme moves the face away from rest
        assert all(not np.allclose(vs.targets[i], vs.rest) for i in spoken), name


def test_smartbody_set_follows_smartbody_table():
    vs = viseme_set("smartbody")
    for phoneme, viseme in SMARTBODY_TABLE.items():
        row = vs.targets[vs.phonemes.index(phoneme)]
        assert vs.channels[int(np.argmax(row))] == viseme and row.max() == 1.0, phoneme


def test_lexemes_and_action_units():
    for lexeme in ("smile", "frown", "surprise", "raised_brows", "blink"):
        assert action_units(lexeme)
    assert action_units("AU12") == {"AU12": 1.0} == action_units("12")
    assert action_units({"smile": 0.5})["AU12"] == 0.5
    with pytest.raises(UsageError, match="unknown expression"):
        action_units("grimace-of-doom")


def _utterance(phones, duration=None):
    """An utterance from (duration_s, phoneme) pairs."""
    t, rows = 0.0, []
    for d, p in phones:
        rows.append((t, t + d, p))
        t += d
    return Utterance(text="", duration_s=duration or t, phonemes=rows)


SYNTHETIC = _utterance([(0.2, "sil"), (0.08, "hh"), (0.12, "aa"), (0.02, "b"), (0.1, "iy"), (0.07, "m"), (0.06, "p"),
                        (0.15, "uw"), (0.4, "sil"), (0.1, "f"), (0.14, "ao"), (0.09, "t"), (0.3, "sil")])


@pytest.mark.parametrize("fps", [24.0, 30.0, 60.0])
@pytest.mark.parametrize("set_name", VISEME_SETS)
def test_lengths_rest_and_closures(set_name, fps):
    times, weights, vs = viseme_curves(SYNTHETIC, set_name, LipSyncSettings(fps=fps))
    # audio and animation lengths agree within one frame, the clip covering the audio
    assert times[0] == 0.0 and SYNTHETIC.duration_s <= times[-1] < SYNTHETIC.duration_s + 1 / fps
    np.testing.assert_allclose(np.diff(times), 1 / fps)
    # silence: rest on the first and last frames and in the middle of the long pause
    np.testing.assert_allclose(weights[0], vs.rest, atol=1e-9)
    np.testing.assert_allclose(weights[-1], vs.rest, atol=1e-9)
    pause = [(s, e) for s, e, p in SYNTHETIC.phonemes if p == SILENCE and 0 < s and e < SYNTHETIC.duration_s][0]
    middle = (times > pause[0] + 0.1) & (times < pause[1] - 0.1)
    assert middle.any()
    np.testing.assert_allclose(weights[middle], np.tile(vs.rest, (middle.sum(), 1)), atol=1e-9)
    # bilabials close fully on at least one frame, even the 20 ms "b"
    runs = [(0.4, 0.42), (0.52, 0.65)]
    for s, e in runs:
        near = (times >= s - 0.5 / fps) & (times <= e + 0.5 / fps)
        assert np.any(np.all(np.abs(weights[near] - vs.closure) < 1e-9, axis=1)), (s, e)
    assert np.all((weights >= 0) & (weights <= 1))


def test_speed_limit_without_delay():
    fps, limit = 30.0, 6.0
    step = np.r_[np.zeros(20), np.ones(20), np.zeros(20)][:, None]
    limited = co.limit_speed(step, limit, fps)
    assert np.abs(np.diff(limited, axis=0)).max() <= limit / fps + 1e-12
    # symmetric: the rise is centred where the step was, no lag
    assert limited[19, 0] == pytest.approx(1 - limited[20, 0]) and limited[40, 0] == pytest.approx(1 - limited[39, 0])
    assert 0 < limited[19, 0] < 0.5
    slow = np.linspace(0, 1, 60)[:, None] * 0.5
    np.testing.assert_allclose(co.limit_speed(slow, limit, fps), slow)


def test_dominance_blend_halfway_at_boundaries():
    starts, ends = np.array([0.0, 0.3]), np.array([0.3, 0.6])
    targets = np.array([[1.0, 0.0], [0.0, 1.0]])
    ones = np.ones(2)
    times = np.array([0.15, 0.3, 0.45])
    w = co.dominance_blend(times, starts, ends, targets, ones, ones * 40, ones * 40, np.zeros(2))
    np.testing.assert_allclose(w[1], [0.5, 0.5])
    assert w[0, 0] > 0.99 and w[2, 1] > 0.99


def test_plain_data_without_a_character():
    result = lipsync(SYNTHETIC)
    assert result.viseme_set == "oculus" and not result.morph_weights and not result.joint_rotations
    sampled = result.sample([0.0, 0.45])
    assert sampled["sil"][0] == pytest.approx(1.0)
    assert [v["viseme"] for v in result.timeline["visemes"]][:3] == ["sil", "aa", "PP"]
    assert result.timeline["frames"] == len(result.times)
    with pytest.raises(UsageError, match="unknown viseme set"):
        viseme_curves(SYNTHETIC, "klingon")


# -- real speech ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def speech():
    require_espeak()
    text = ("The old lighthouse keeper climbed the spiral stairs every evening at dusk. He carried a small brass lamp, "
            "a notebook, and a thermos of sweet black tea. From the gallery at the top he could see the whole bay: "
            "the fishing boats coming home, and the gulls circling over the harbour.")
    return tts_engine("espeak").synthesize(text)


def viseme_onsets(utterance, times, weights, vs, min_s=0.06):
    """(phoneme start, onset) pairs: where the channel of a phoneme's viseme overtakes the channel of the
    viseme before it, for neighbours (no transparent phoneme between) that both last ``min_s`` or more."""
    pairs, prev = [], None
    for s, e, p in utterance.phonemes:
        v = phoneme_viseme(p)
        if not v:
            prev = None
            continue
        if prev is not None and v != prev[0] and e - s >= min_s and prev[1] >= min_s:
            diff = weights[:, vs.channels.index(v)] - weights[:, vs.channels.index(prev[0])]
            lo, hi = np.searchsorted(times, s - 0.1), min(np.searchsorted(times, e), len(times) - 1)
            seg, ts = diff[lo:hi + 1], times[lo:hi + 1]
            up = np.flatnonzero((seg[:-1] <= 0) & (seg[1:] > 0))
            assert len(up), f"the viseme of {p!r} at {s:.3f} s never shows"
            i = up[np.argmin(np.abs(ts[up] - s))]
            pairs.append((s, ts[i] - seg[i] * (ts[i + 1] - ts[i]) / (seg[i + 1] - seg[i])))
        prev = (v, e - s)
    return np.array(pairs)


@pytest.mark.parametrize("fps", [24.0, 30.0, 60.0])
def test_viseme_onsets_within_20_ms_of_their_phonemes(speech, fps):
    times, weights, vs = viseme_curves(speech, "oculus", LipSyncSettings(fps=fps))
    pairs = viseme_onsets(speech, times, weights, vs)
    assert len(pairs) > 60
    error = pairs[:, 1] - pairs[:, 0]
    assert np.abs(error).max() <= 0.020, f"worst onset {1000 * error[np.argmax(np.abs(error))]:.1f} ms"
    assert abs(np.median(error)) < 0.005
    print(f"{len(pairs)} onsets at {fps:g} fps: worst {1000 * np.abs(error).max():.1f} ms")


def test_real_speech_closures_and_pauses(speech):
    for set_name in ("oculus", "arkit", "jaw"):
        times, weights, vs = viseme_curves(speech, set_name)
        closed = np.all(np.abs(weights - vs.closure) < 1e-9, axis=1)
        at_rest = np.all(np.abs(weights - vs.rest) < 1e-9, axis=1)
        for s, e, p in speech.phonemes:
            if p in ("p", "b", "m"):
                near = (times >= s - 1 / 60) & (times <= e + 1 / 60)
                assert closed[near].any(), (set_name, p, s)
            if p == SILENCE and e - s >= 0.25:
                assert at_rest[(times > s + 0.1) & (times < e - 0.1)].all(), (set_name, s)
        assert at_rest[0] and at_rest[-1]
