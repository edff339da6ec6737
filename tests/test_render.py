"""The render engine on skeletons and motions built here: sizes, frame counts, where pixels land."""
from __future__ import annotations

import io
import os
import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image

from infuse import Motion, Skeleton
from infuse import quaternions as quat
from infuse.errors import MissingFeatureError, UsageError
from infuse.render import (
    Camera, Figure, Marker, Progress, Renderer, Style, default_sides, render, select_times, sides_from_mapping,
)

BACKGROUND = np.array(Style().background)

# name, parent, rest offset in metres (+X is the character's left, +Y up, +Z forward)
JOINTS = [
    ("Hips", None, (0.0, 0.95, 0.0)),
    ("Spine", "Hips", (0.0, 0.12, 0.0)), ("Chest", "Spine", (0.0, 0.2, 0.0)), ("Neck", "Chest", (0.0, 0.2, 0.0)),
    ("Head", "Neck", (0.0, 0.1, 0.0)),
    ("LeftShoulder", "Chest", (0.18, 0.15, 0.0)), ("LeftElbow", "LeftShoulder", (0.0, -0.28, 0.0)),
    ("LeftWrist", "LeftElbow", (0.0, -0.25, 0.0)),
    ("RightShoulder", "Chest", (-0.18, 0.15, 0.0)), ("RightElbow", "RightShoulder", (0.0, -0.28, 0.0)),
    ("RightWrist", "RightElbow", (0.0, -0.25, 0.0)),
    ("LeftHip", "Hips", (0.1, -0.05, 0.0)), ("LeftKnee", "LeftHip", (0.0, -0.42, 0.0)),
    ("LeftAnkle", "LeftKnee", (0.0, -0.42, 0.0)), ("LeftToe", "LeftAnkle", (0.0, -0.06, 0.12)),
    ("RightHip", "Hips", (-0.1, -0.05, 0.0)), ("RightKnee", "RightHip", (0.0, -0.42, 0.0)),
    ("RightAnkle", "RightKnee", (0.0, -0.42, 0.0)), ("RightToe", "RightAnkle", (0.0, -0.06, 0.12)),
]


def make_skeleton(scale: float = 1.0) -> Skeleton:
    names = [j[0] for j in JOINTS]
    parents = [-1 if p is None else names.index(p) for _, p, _ in JOINTS]
    ends = [names.index("Head"), names.index("LeftToe"), names.index("RightToe")]
    offsets = np.array([j[2] for j in JOINTS]) * scale
    return Skeleton(names, parents, offsets, quat.identity((len(names),)), ends,
                    np.array([(0, 0.2, 0), (0, 0, 0.05), (0, 0, 0.05)]) * scale)


def make_walk(skeleton: Skeleton, frames: int = 60, fps: float = 30.0, speed: float = 1.2) -> Motion:
    """Legs and arms swinging about X once a second while the hips move forward (+Z) at ``speed`` m/s."""
    t = np.arange(frames) / fps
    phase = 2 * np.pi * t
    rots = quat.identity((frames, skeleton.num_joints))
    x_axis = np.tile([1.0, 0.0, 0.0], (frames, 1))
    for name, amp, shift in (("LeftHip", -0.5, 0.0), ("RightHip", -0.5, np.pi),
                             ("LeftShoulder", 0.4, np.pi), ("RightShoulder", 0.4, 0.0)):
        rots[:, skeleton.index[name]] = quat.from_axis_angle(x_axis, amp * np.sin(phase + shift))
    for name, shift in (("LeftKnee", 1.5), ("RightKnee", 1.5 + np.pi)):
        rots[:, skeleton.index[name]] = quat.from_axis_angle(x_axis, 0.5 + 0.5 * np.sin(phase + shift))
    root = np.stack([np.zeros(frames), np.full(frames, skeleton.rest_translations[0, 1]), speed * t], axis=1)
    return Motion(skeleton, fps, rots, root, name="walk")


def non_background(image: Image.Image, xy, radius: int = 2) -> bool:
    """Whether any pixel within ``radius`` of ``xy`` differs clearly from the background."""
    a = np.asarray(image.convert("RGB")).astype(int)
    x, y = int(round(xy[0])), int(round(xy[1]))
    patch = a[max(y - radius, 0):y + radius + 1, max(x - radius, 0):x + radius + 1]
    return bool(np.any(np.abs(patch - BACKGROUND).sum(axis=-1) > 60))


@pytest.fixture(scope="module")
def skeleton():
    return make_skeleton()


@pytest.fixture(scope="module")
def walk(skeleton):
    return make_walk(skeleton)


def test_still_png_size_and_joints_where_projected(tmp_path, skeleton):
    fig = Figure.from_skeleton(skeleton, label="rest")
    out = render([fig], tmp_path / "rest.png", size=(320, 400), camera=Camera(view="front"))
    img = Image.open(out)
    assert img.size == (320, 400) and img.format == "PNG"
    renderer = Renderer([fig], [0.0], size=(320, 400), camera=Camera(view="front"))
    pix = renderer.joint_pixels(0, 0)
    head, hips = pix[skeleton.index["Head"]], pix[skeleton.index["Hips"]]
    left, right = pix[skeleton.index["LeftWrist"]], pix[skeleton.index["RightWrist"]]
    assert head[1] < hips[1]  # +Y is up in the picture
    assert left[0] > right[0]  # seen from the front, the character's left is on the image's right
    for joint in ("Head", "LeftWrist", "RightToe", "Hips"):
        assert non_background(img, pix[skeleton.index[joint]]), joint
    top_of_head = pix[skeleton.num_joints]  # the head's end site
    assert non_background(img, top_of_head)
    assert not non_background(img, (head[0] + 0.3 * (320 - head[0]), head[1]), radius=1)  # beside the head: empty
    # the figure is framed: it spans a good part of the height and stays inside the image
    ys = pix[:, 1]
    assert ys.min() > 0 and ys.max() < 400 and ys.max() - ys.min() > 200


def test_left_side_lighter_than_right(tmp_path, skeleton):
    fig = Figure.from_skeleton(skeleton)
    renderer = Renderer([fig], [0.0], size=(320, 400), camera=Camera(view="front"), style=Style(show_shadow=False))
    img = np.asarray(renderer.image(0)).astype(int)
    pix = renderer.joint_pixels(0, 0)

    def colour_between(a, b):
        mid = (pix[skeleton.index[a]] + pix[skeleton.index[b]]) / 2
        return img[int(round(mid[1])), int(round(mid[0]))].sum()

    assert colour_between("LeftElbow", "LeftWrist") > colour_between("RightElbow", "RightWrist") + 60
    assert list(default_sides(skeleton)[[skeleton.index[n] for n in ("LeftWrist", "RightWrist", "Head")]]) == [1, -1, 0]


def test_sides_from_a_first_frame_when_rest_is_not_upright():
    sk = make_skeleton()
    lying = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), -np.pi / 2)  # every bone along X at rest
    flat = sk.transformed(rotation=lying)
    stand = quat.multiply(quat.conjugate(lying), flat.rest_rotations[0])
    rots = np.array(flat.rest_rotations)[None].copy()
    rots[0, 0] = stand
    motion = Motion(flat, 30.0, rots, flat.rest_translations[0][None])
    fig = Figure.from_motion(motion)
    assert fig.sides[sk.index["LeftWrist"]] == 1 and fig.sides[sk.index["RightWrist"]] == -1


def test_sides_from_mapping_follow_ancestors(skeleton):
    class FakeMapping:
        def mapped(self):
            return {"l_shoulder": "LeftShoulder", "r_shoulder": "RightShoulder", "spine1": "Spine"}

    sides = sides_from_mapping(skeleton, FakeMapping())
    assert sides[skeleton.index["LeftWrist"]] == 1  # unmapped, inherits its shoulder's side
    assert sides[skeleton.index["RightElbow"]] == -1
    assert sides[skeleton.index["Head"]] == 0


def test_gif_size_frame_count_and_motion(tmp_path, walk):
    out = render([Figure.from_motion(walk)], tmp_path / "walk.gif", size=(200, 160), fps=15)
    img = Image.open(out)
    expected = len(select_times([Figure.from_motion(walk)], fps=15))
    assert expected == int(walk.duration * 15) + 1
    assert img.size == (200, 160) and img.n_frames == expected
    assert img.info["duration"] == 70 and img.info.get("loop") == 0
    img.seek(0)
    first = np.asarray(img.convert("RGB")).copy()
    img.seek(expected // 2)
    middle = np.asarray(img.convert("RGB"))
    assert np.abs(first.astype(int) - middle).sum(axis=-1).astype(bool).mean() > 0.005


def test_two_frames_of_a_moving_clip_differ_where_the_figure_moved(walk):
    fig = Figure.from_motion(walk)
    renderer = Renderer([fig], np.array([0.0, 0.5]), size=(320, 240), camera=Camera(view="side", follow=False))
    a, b = (np.asarray(renderer.image(k)).astype(int) for k in range(2))
    knee0 = renderer.joint_pixels(0, 0)[walk.skeleton.index["LeftKnee"]]
    knee1 = renderer.joint_pixels(0, 1)[walk.skeleton.index["LeftKnee"]]
    assert knee1[0] > knee0[0] + 5  # side view from the right: walking forward (+Z) moves right
    assert np.abs(a - b).sum() > 0


def test_filmstrip_tiles(tmp_path, walk):
    out = render([Figure.from_motion(walk)], tmp_path / "strip.png", strip=5, size=(120, 180), title="walk strip")
    w, h = Image.open(out).size
    assert w == 5 * 120 and h > 180  # one row of tiles under a title row
    times = select_times([Figure.from_motion(walk)], count=5)
    assert times[0] == 0.0 and np.isclose(times[-1], walk.duration)


def test_markers_and_rays_are_drawn(skeleton):
    target = np.array([0.6, 1.7, 0.0])  # beside the head, in empty space
    marked = Figure.from_skeleton(skeleton, markers=[Marker(target, "gaze", color=(220, 0, 0), style="sphere", size=0.05,
                                                            ray_from="Head")])
    renderer = Renderer([marked], [0.0], size=(400, 400), camera=Camera(view="front"))
    img = np.asarray(renderer.image(0)).astype(int)
    reddish = (img[..., 0] > 150) & (img[..., 1] < 90) & (img[..., 2] < 90)
    mx, my = (int(round(v)) for v in renderer.panels[0].view.project(target[None], 0)[0][0] / renderer.ss)
    assert reddish[my - 2:my + 3, mx - 2:mx + 3].any()
    # the dashed ray: red pixels halfway between the head and the target
    head = renderer.joint_pixels(0, 0)[skeleton.index["Head"]]
    x0, y0 = (int(v) for v in (head + np.array([mx, my])) / 2)
    assert reddish[y0 - 6:y0 + 7, x0 - 12:x0 + 13].any()
    # and nothing red anywhere else: the figure and the ground are not red
    ys, xs = np.nonzero(reddish)
    dx, dy = np.array([mx, my]) - head
    on_line = np.abs((xs - head[0]) * dy - (ys - head[1]) * dx) / np.hypot(dx, dy)  # distance to the head-target line
    assert np.all((on_line < 6) | (np.hypot(xs - mx, ys - my) < 40))


def test_cross_marker_moving(skeleton, walk):
    path = np.stack([np.full(60, -0.5), np.full(60, 2.0), np.linspace(0, 2, 60)], axis=1)  # above the walker's head
    fig = Figure.from_motion(walk, markers=[Marker(path, "reach", color=(0, 0, 230))])
    renderer = Renderer([fig], np.array([0.0, 1.9]), size=(320, 240), camera=Camera(view="side", follow=False))
    for t in range(2):
        img = np.asarray(renderer.image(t)).astype(int)
        p = renderer.panels[0].view.project(fig.markers[0].at(renderer.frames[0][t:t + 1]), t)[0][0] / renderer.ss
        patch = img[int(p[1]) - 2:int(p[1]) + 3, int(p[0]) - 2:int(p[0]) + 3].reshape(-1, 3)
        assert np.any((patch[:, 2] > 150) & (patch[:, 0] < 90)), t


def test_contacts_colour_the_foot(walk):
    sk = walk.skeleton
    on = np.zeros(walk.num_frames, dtype=bool)
    on[:10] = True
    fig = Figure.from_motion(walk, contacts={"LeftAnkle": on}, color=(40, 40, 200))
    renderer = Renderer([fig], np.array([0.0, 1.0]), size=(400, 300), camera=Camera(view="side", follow=False),
                        style=Style(show_shadow=False))
    green = np.array(Style().contact)
    for t, expect in ((0, True), (1, False)):
        img = np.asarray(renderer.image(t)).astype(int)
        x, y = (int(round(v)) for v in renderer.joint_pixels(0, t)[sk.index["LeftAnkle"]])
        patch = img[y - 2:y + 3, x - 2:x + 3].reshape(-1, 3)
        assert bool(np.any(np.abs(patch - green).sum(axis=-1) < 40)) == expect


def test_side_by_side_panels_share_one_scale(skeleton):
    small, big = Figure.from_skeleton(skeleton, label="small"), Figure.from_skeleton(make_skeleton(2.0), label="big")
    renderer = Renderer([small, big], [0.0], size=(600, 400), camera=Camera(view="front"))
    h_small = np.ptp(renderer.joint_pixels(0, 0)[:, 1])
    h_big = np.ptp(renderer.joint_pixels(1, 0)[:, 1])
    assert h_big == pytest.approx(2.0 * h_small, rel=0.02)
    assert renderer.joint_pixels(0, 0)[:, 0].max() < 300 < renderer.joint_pixels(1, 0)[:, 0].min()


def test_overlay_draws_near_over_far(skeleton):
    near = Figure.from_skeleton(make_skeleton().transformed(), color=(230, 20, 20))
    far_positions = near.positions + np.array([0.0, 0.0, -0.5])  # same pose, further from a front camera
    far = Figure(skeleton, far_positions, end_sites=near.end_sites + np.array([0.0, 0.0, -0.5]), color=(20, 20, 230))
    for order in ([near, far], [far, near]):
        renderer = Renderer(order, [0.0], overlay=True, size=(300, 400), camera=Camera(view="front"),
                            style=Style(show_shadow=False, show_grid=False))
        img = np.asarray(renderer.image(0)).astype(int)
        x, y = (int(round(v)) for v in renderer.joint_pixels(0, 0)[[skeleton.index["Spine"], skeleton.index["Chest"]]].mean(axis=0))
        r, g, b = img[y, x]
        assert r > b + 40  # the red figure is nearer: it covers the blue one whichever was given first


def test_perspective_makes_near_things_bigger(skeleton):
    fig = Figure.from_skeleton(skeleton)
    renderer = Renderer([fig], [0.0], size=(300, 400), camera=Camera(view="side", projection="perspective"))
    pix = renderer.joint_pixels(0, 0)
    # seen from the right side, the right shoulder-to-wrist arm is nearer than the left: it looks longer
    arm = lambda a, b: np.linalg.norm(pix[skeleton.index[a]] - pix[skeleton.index[b]])  # noqa: E731
    assert arm("RightShoulder", "RightWrist") > arm("LeftShoulder", "LeftWrist") * 1.02


def test_follow_keeps_the_walker_in_the_middle():
    sk = make_skeleton()
    long_walk = make_walk(sk, frames=150, speed=2.0)  # 10 m
    fig = Figure.from_motion(long_walk)
    times = np.array([0.0, 2.5, 4.9])
    follow = Renderer([fig], times, size=(300, 300), camera=Camera(view="side"))  # auto: follows
    still = Renderer([fig], times, size=(300, 300), camera=Camera(view="side", follow=False))
    xs_follow = [follow.joint_pixels(0, t)[0, 0] for t in range(3)]
    xs_still = [still.joint_pixels(0, t)[0, 0] for t in range(3)]
    assert np.ptp(xs_follow) < 40 and np.ptp(xs_still) > 150


def test_non_rigid_root_link_is_not_drawn():
    """A root that stays at the origin while the hips walk away (some BVH files) is no bone."""
    base = make_skeleton()
    names = ("Root",) + base.names
    parents = np.concatenate([[-1], base.parents + 1])
    parents[1] = 0
    trans = np.concatenate([[[0, 0, 0]], base.rest_translations])
    sk = Skeleton(names, parents, trans, quat.identity((len(names),)))
    frames = 30
    jt = np.broadcast_to(trans, (frames, len(names), 3)).copy()
    jt[:, 1, 2] = np.linspace(3.0, 6.0, frames)  # the hips travel 3..6 m away from the root
    motion = Motion(sk, 30.0, quat.identity((frames, len(names))), np.zeros((frames, 3)), joint_translations=jt)
    fig = Figure.from_motion(motion)
    assert (0, 1) not in {tuple(b) for b in fig.bones} and not fig.visible[0] and fig.root == 1
    renderer = Renderer([fig], [0.0], size=(200, 300), camera=Camera(view="front"))
    ys = renderer.joint_pixels(0, 0)[1:, 1]
    assert np.ptp(ys) > 150  # framed on the body, not on the far-away root


def test_names_and_highlight(skeleton):
    fig = Figure.from_skeleton(skeleton, names=["Head"], highlight=["LeftWrist"])
    bare = Figure.from_skeleton(skeleton)
    cam = Camera(view="front")
    a = np.asarray(Renderer([fig], [0.0], size=(320, 400), camera=cam).image(0)).astype(int)
    b = np.asarray(Renderer([bare], [0.0], size=(320, 400), camera=cam).image(0)).astype(int)
    pix = Renderer([fig], [0.0], size=(320, 400), camera=cam).joint_pixels(0, 0)
    changed = np.abs(a - b).sum(axis=-1) > 30
    hx, hy = (int(v) for v in pix[skeleton.index["Head"]])
    assert changed[hy - 15:hy + 15, hx:hx + 60].sum() > 20  # the name's text beside the head
    wx, wy = (int(v) for v in pix[skeleton.index["LeftWrist"]])
    ring = a[wy - 12:wy + 13, wx - 12:wx + 13].reshape(-1, 3)
    assert np.any(np.abs(ring - np.array(Style().highlight)).sum(axis=-1) < 60)
    with pytest.raises(ValueError, match="unknown joint"):
        Figure.from_skeleton(skeleton, names=["Tail"])


def test_select_times_rules(walk):
    figs = [Figure.from_motion(walk)]
    assert list(select_times(figs, frame=30, still=True)) == [1.0]
    assert len(select_times(figs, start=0.5, end=1.0, fps=10)) == 6
    with pytest.raises(UsageError):
        select_times(figs, frame=600, still=True)
    with pytest.raises(UsageError):
        select_times(figs, start=1.5, end=0.5)
    with pytest.raises(UsageError):
        select_times(figs, start=100.0)


def test_bad_suffix_and_strip_misuse(tmp_path, walk):
    fig = Figure.from_motion(walk)
    with pytest.raises(UsageError, match=r"\.png, \.gif or \.mp4"):
        render([fig], tmp_path / "out.jpg")
    with pytest.raises(UsageError):
        render([fig], tmp_path / "out.gif", strip=4)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed (scripts/setup.sh installs it)")
def test_mp4_size_and_frame_count(tmp_path, walk):
    out = render([Figure.from_motion(walk)], tmp_path / "walk.mp4", size=(321, 241), fps=20)
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                            "stream=nb_read_frames,width,height,codec_name,pix_fmt", "-of", "default=nw=1", str(out)],
                           capture_output=True, text=True, check=True).stdout
    fields = dict(line.split("=", 1) for line in probe.split())
    assert fields["codec_name"] == "h264" and fields["pix_fmt"] == "yuv420p"
    assert (int(fields["width"]), int(fields["height"])) == (322, 242)  # padded to even sides for yuv420p
    assert int(fields["nb_read_frames"]) == int(walk.duration * 20) + 1


def test_mp4_without_ffmpeg_says_how_to_install(tmp_path, walk, monkeypatch):
    monkeypatch.setenv("INFUSE_FFMPEG", str(tmp_path / "no-such-ffmpeg"))
    with pytest.raises(MissingFeatureError, match="apt-get install ffmpeg"):
        render([Figure.from_motion(walk)], tmp_path / "walk.mp4")
    assert not (tmp_path / "walk.mp4").exists()


def test_progress_reports_frames_rate_and_time_left():
    stream = io.StringIO()
    with Progress(4, "render x", enabled=True, stream=stream) as bar:
        for _ in range(4):
            bar.advance()
    lines = stream.getvalue().splitlines()
    # asked for on a log stream: the first line at once, the last when done, none in between
    assert len(lines) == 2 and lines[0].startswith("render x  25% [#####...............] 1/4 left ")
    assert lines[-1].startswith("render x 100% [") and "] 4/4 left 0:00 elapsed 0:00" in lines[-1] and "frames/s" in lines[-1]
    quiet = io.StringIO()
    Progress(4, stream=quiet).advance()  # not a terminal and not asked for: silent
    assert quiet.getvalue() == ""


def test_progress_on_a_terminal_redraws_one_line_that_fits(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr("shutil.get_terminal_size", lambda *a: os.terminal_size((40, 20)))
    stream = Terminal()
    with Progress(3, "batch", stream=stream, unit="items", also=("clip-frames",)) as bar:
        bar.advance(1, 500)
        bar.advance(2, 1000)
    text = stream.getvalue()
    assert text.endswith("\n") and text.count("\n") == 1  # redrawn in place, one newline at the end
    drawn = [part.removesuffix("\x1b[K") for part in text.strip().split("\r") if part]
    assert drawn[-1].startswith("batch 100% [") and all(len(part) <= 39 for part in drawn)


def test_figure_validates_shapes(skeleton):
    with pytest.raises(ValueError, match="positions"):
        Figure(skeleton, np.zeros((3, 5, 3)))
    with pytest.raises(ValueError, match="NaN"):
        Figure(skeleton, np.full((1, skeleton.num_joints, 3), np.nan))
    with pytest.raises(ValueError, match="contact"):
        Figure.from_skeleton(skeleton, contacts={"LeftAnkle": [True, False]})
    with pytest.raises(ValueError, match="style"):
        Marker((0, 0, 0), style="star")
    with pytest.raises(ValueError, match="unknown joint 'Eye'"):
        Figure.from_skeleton(skeleton, markers=[Marker((0, 1, 1), ray_from="Eye")])


def test_named_views_put_the_character_where_expected(skeleton):
    fig = Figure.from_skeleton(skeleton)
    idx = skeleton.index

    def pix(view):
        return Renderer([fig], [0.0], size=(300, 300), camera=Camera(view=view)).joint_pixels(0, 0)

    side = pix("side")  # from the character's right: the toes (+Z) point to the image's right
    assert side[idx["LeftToe"], 0] > side[idx["LeftAnkle"], 0] + 5
    top = pix("top")  # a map: forward is up, the character's left on the image's left
    assert top[idx["LeftToe"], 1] < top[idx["LeftAnkle"], 1] - 5
    assert top[idx["LeftShoulder"], 0] < top[idx["RightShoulder"], 0] - 20
    quarter = pix("three-quarter")  # from the front-right: the left side is further right and the head up
    assert quarter[idx["LeftShoulder"], 0] > quarter[idx["RightShoulder"], 0]
    assert quarter[idx["Head"], 1] < quarter[idx["Hips"], 1]
