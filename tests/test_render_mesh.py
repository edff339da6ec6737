"""Mesh renders: skinned surfaces read from glTF, posed by a clip, rasterized and lit; ``--style``.

Real characters (Xbot, a Ready Player Me avatar) play a BVH walk retargeted onto them and written
as GLB; small synthetic cases pin the rasterizer and the skinning maths.
"""
from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest
from PIL import Image
from scipy.ndimage import distance_transform_edt

import infuse
from corpus_data import corpus_file, require_corpus
from infuse import quaternions as quat
from infuse.cli import main
from infuse.mapping import map_skeleton
from infuse.mesh import SkinnedMesh, merge
from infuse.render import Camera, Figure, Renderer, Style
from infuse.render.meshes import FigureMesh
from infuse.render.raster import coverage, rasterize

WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
XBOT = "runxaway-models/Xbot.glb"
AVATAR = "talkinghead/avatars/brunette-t.glb"
VROID = "talkinghead/avatars/vroid.glb"  # meshopt-compressed: triangle codes, octahedral normals, quantized
CLIP = "dataset-1_walk_normal_001"
BARE = Style(show_grid=False, show_shadow=False, show_trail=False)  # only the figure differs from the background


def cli(capsys, *argv) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def walkers(tmp_path_factory) -> dict[str, "infuse.Asset"]:
    """Xbot and the avatar playing the BVH walk, retargeted and written as GLB, read back."""
    require_corpus()
    out = tmp_path_factory.mktemp("walkers")
    assets = {}
    for name, character in (("xbot", XBOT), ("avatar", AVATAR)):
        path = out / f"{name}_walk.glb"
        assert main(["retarget", str(corpus_file(WALK)), "--to", str(corpus_file(character)), "-o", str(path)]) == 0
        assets[name] = infuse.load(path)
    return assets


def silhouette(image: Image.Image) -> np.ndarray:
    """(H, W) bool: pixels that are not the background."""
    a = np.asarray(image.convert("RGB")).astype(int)
    return np.abs(a - np.array(BARE.background)).sum(axis=-1) > 12


@pytest.mark.parametrize("name", ["xbot", "avatar"])
def test_mesh_plays_the_clip_covers_the_skeleton_and_is_shaded(walkers, name):
    asset = walkers[name]
    motion = asset.motions[CLIP]
    figure = Figure.from_motion(motion, meshes=asset.meshes)
    renderer = Renderer([figure], np.array([0.5, 1.0]), size=(640, 480), style=BARE, counter=False,
                        camera=Camera(follow=False))
    images = [renderer.image(t, labels=False) for t in range(2)]
    masks = [silhouette(im) for im in images]
    changed = np.any(np.asarray(images[0]) != np.asarray(images[1]), axis=-1)
    assert changed.mean() > 0.01  # the character walked between the two times
    for t, (image, mask) in enumerate(zip(images, masks)):
        assert 0.02 < mask.mean() < 0.5
        joints = renderer.joint_pixels(0, t)[: asset.skeleton.num_joints][figure.visible[: asset.skeleton.num_joints]]
        # every joint of the stick figure lies on the surface's silhouette, or a few pixels from it (toe tips)
        gap = distance_transform_edt(~mask)
        x, y = np.clip(np.rint(joints).astype(int), 0, [639, 479]).T
        assert gap[y, x].max() <= 5.0, asset.skeleton.names[int(np.argmax(gap[y, x]))]
        assert np.mean(gap[y, x] == 0) > 0.85  # the rest: leaf tips (head top, toe and finger ends) on the outline
        # the head is at the top of the silhouette: +Y is up on screen
        rows = np.flatnonzero(mask.any(axis=1))
        assert rows[0] < joints[:, 1].min() + 0.1 * (rows[-1] - rows[0])
        # shaded, not a flat fill
        pixels = np.asarray(image.convert("RGB"))[mask].astype(float)
        assert len(np.unique(pixels.astype(np.uint8), axis=0)) > 200
        assert pixels.mean(axis=1).std() > 12.0


def test_avatar_colours_come_from_its_textures(walkers):
    asset = walkers["avatar"]
    colours = {m.name: m.vertex_colors()[:, :3].mean(axis=0) for m in asset.meshes}
    assert all(m.colors is not None for m in asset.meshes)  # every surface has a base colour texture
    hair, skin = colours["Wolf3D_Hair"], colours["Wolf3D_Head"]
    assert hair.sum() < 0.2 < skin.sum() and skin[0] > skin[2]  # dark hair, warm skin


def test_meshopt_compressed_surfaces_are_decoded():
    require_corpus()
    avatar = infuse.load(corpus_file(VROID))
    meshes = avatar.meshes
    assert meshes and not [w for w in avatar.warnings if "not drawn" in w]
    body = max(meshes, key=lambda m: m.num_triangles if m.name.startswith("Body") else 0)
    edges = np.sort(body.triangles[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    assert (uses == 2).mean() > 0.75  # a closed skin: most edges join two triangles (a wrong decode joins none)
    assert np.allclose(np.linalg.norm(body.normals, axis=1), 1.0, atol=1e-3)
    figure = Figure.from_skeleton(avatar.skeleton, meshes=meshes)
    renderer = Renderer([figure], np.zeros(1), size=(400, 300), style=BARE, counter=False, title="")
    mask = silhouette(renderer.image(0, labels=False))
    # the body's joints (the rig also has skirt and coat bones this outfit has no cloth for)
    body_joints = [avatar.skeleton.index[j] for j in map_skeleton(avatar).mapped().values()]
    assert len(body_joints) > 30
    x, y = np.clip(np.rint(renderer.joint_pixels(0, 0)[body_joints]).astype(int), 0, [399, 299]).T
    assert distance_transform_edt(~mask)[y, x].max() <= 5.0


def test_rest_pose_is_upright_and_skinning_reproduces_the_bind_pose():
    require_corpus()
    xbot = infuse.load(corpus_file(XBOT))
    sk = xbot.skeleton
    positions = np.concatenate([m.positions for m in xbot.meshes])
    lo, hi = positions.min(axis=0), positions.max(axis=0)
    assert abs(lo[1]) < 0.02 and 1.7 < hi[1] < 1.9  # metres, feet on the ground, +Y up
    assert hi[1] > sk.rest_global_positions[sk.index["mixamorig:Head"], 1] + 0.1  # the skull is above the head joint
    for mesh in xbot.meshes:  # Xbot is bound in its rest pose: skinning at rest changes nothing
        posed, normals = mesh.skin(sk.rest_global_rotations[None], sk.rest_global_positions[None])
        assert np.abs(posed[0] - mesh.positions).max() < 1e-5
        assert np.abs(normals[0] - mesh.normals).max() < 1e-4


def test_avatar_bound_in_another_pose_keeps_its_limbs_on_the_skeleton():
    """The avatar's rest pose differs from its bind pose by up to 107 degrees (arms): skinned at rest,
    every joint still sits inside the surface."""
    require_corpus()
    avatar = infuse.load(corpus_file(AVATAR))
    assert avatar.meta["bind_pose"]["matches_rest"] is False
    sk = avatar.skeleton
    body = [m for m in avatar.meshes if m.name.startswith(("Wolf3D_Body", "Wolf3D_Outfit", "Wolf3D_Head"))]
    posed = np.concatenate([m.skin(sk.rest_global_rotations[None], sk.rest_global_positions[None])[0][0] for m in body])
    distance = np.linalg.norm(sk.rest_global_positions[:, None] - posed[None], axis=-1).min(axis=1)
    assert distance.max() < 0.12, sk.names[int(np.argmax(distance))]


def test_surfaces_face_outwards():
    """Seen from the front, the visible surface is wound counter-clockwise and its normals face the camera."""
    require_corpus()
    xbot = infuse.load(corpus_file(XBOT))
    mesh = merge(xbot.meshes)
    basis = Camera(view="front").basis()
    cam = mesh.positions.astype(np.float64) @ basis.T
    pixels = np.stack([cam[:, 0], -cam[:, 1]], axis=1) * 250.0 + [200.0, 250.0]  # x right, y down
    fragments = rasterize(pixels, cam[:, 2], mesh.triangles, (400, 500))
    corner = pixels[mesh.triangles[fragments.triangle]]
    e1, e2 = corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0]
    counter_clockwise = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0  # y runs down the image
    assert counter_clockwise.mean() > 0.97
    normals = (mesh.normals[mesh.triangles[fragments.triangle]] * fragments.barycentric[..., None]).sum(axis=1)
    assert (normals @ basis[2] > 0).mean() > 0.97


def test_morph_targets_move_only_their_surfaces():
    require_corpus()
    avatar = infuse.load(corpus_file(AVATAR))
    sk = avatar.skeleton
    rot, pos = sk.rest_global_rotations[None], sk.rest_global_positions[None]
    still = FigureMesh(avatar.meshes, rot, pos)
    open_jaw = FigureMesh(avatar.meshes, rot, pos, {"jawOpen": np.ones(1), "not a target": np.ones(1)})
    moved = np.linalg.norm(open_jaw.pose([0])[0][0] - still.pose([0])[0][0], axis=1)
    assert moved.max() > 0.005  # the jaw drops by millimetres to centimetres
    names = np.concatenate([[m.name] * m.num_vertices for m in avatar.meshes if m.num_triangles])
    assert set(names[moved > 1e-6]) <= {"Wolf3D_Head", "Wolf3D_Teeth", "EyeLeft", "EyeRight"}


def test_style_auto_draws_a_stick_figure_without_a_mesh_and_mesh_style_refuses(tmp_path, capsys):
    require_corpus()
    bvh = corpus_file(WALK)
    code, _, err = cli(capsys, "render", bvh, "-o", tmp_path / "auto.png", "--size", "200x150")
    assert code == 0, err
    code, _, err = cli(capsys, "render", bvh, "-o", tmp_path / "stick.png", "--size", "200x150", "--style", "stick")
    assert code == 0, err
    assert np.array_equal(np.asarray(Image.open(tmp_path / "auto.png")), np.asarray(Image.open(tmp_path / "stick.png")))
    code, _, err = cli(capsys, "render", bvh, "-o", tmp_path / "mesh.png", "--style", "mesh")
    assert code == 3 and "has no skinned mesh to draw" in err and "--style stick" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "mesh.png").exists()


def test_style_auto_draws_the_mesh_of_a_character(walkers, tmp_path, capsys):
    """Auto and mesh agree on a file with a mesh; the stick figure is another picture."""
    path = walkers["xbot"].path
    outputs = {}
    for style in ("auto", "mesh", "stick"):
        out = tmp_path / f"{style}.png"
        code, _, err = cli(capsys, "render", path, "--clip", CLIP, "--frame", "30", "-o", out, "--size", "240x180",
                           "--style", style)
        assert code == 0, err
        outputs[style] = np.asarray(Image.open(out))
    assert np.array_equal(outputs["auto"], outputs["mesh"])
    assert not np.array_equal(outputs["auto"], outputs["stick"])


def test_gif_and_mp4_have_one_frame_per_time(walkers, tmp_path, capsys):
    path = walkers["avatar"].path
    code, _, err = cli(capsys, "render", path, "-o", tmp_path / "walk.gif", "--start", "1", "--end", "2", "--fps", "10",
                       "--size", "160x120", "--progress")
    assert code == 0, err
    assert "11/11 left" in err  # the progress line
    gif = Image.open(tmp_path / "walk.gif")
    assert gif.n_frames == 11 and gif.size == (160, 120)
    if shutil.which("ffprobe") is None:
        pytest.skip("ffprobe (part of ffmpeg) is not installed")
    code, _, err = cli(capsys, "render", path, "-o", tmp_path / "walk.mp4", "--end", "1", "--fps", "12", "--size", "160x120")
    assert code == 0, err
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                            "stream=nb_read_frames,width,height", "-of", "json", str(tmp_path / "walk.mp4")],
                           capture_output=True, text=True, check=True)
    stream = json.loads(probe.stdout)["streams"][0]
    assert (int(stream["nb_read_frames"]), stream["width"], stream["height"]) == (13, 160, 120)


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_a_render_that_fails_half_way_leaves_no_file(walkers, tmp_path, monkeypatch, suffix):
    from infuse.render import ffmpeg_path, render

    if suffix == ".mp4":
        try:
            ffmpeg_path()
        except infuse.errors.MissingFeatureError:
            pytest.skip("ffmpeg is not installed")
    asset = walkers["xbot"]
    figure = Figure.from_motion(asset.motions[CLIP], meshes=asset.meshes)
    out = tmp_path / f"walk{suffix}"
    out.write_bytes(b"the previous render")
    drawn = []
    original = Renderer.image

    def failing(self, t, labels=True):
        drawn.append(t)
        if len(drawn) > 5:
            raise RuntimeError("disk on fire")
        return original(self, t, labels)

    monkeypatch.setattr(Renderer, "image", failing)
    with pytest.raises(RuntimeError, match="disk on fire"):
        render([figure], out, end=1.0, fps=10, size=(120, 90))
    assert out.read_bytes() == b"the previous render"
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temporary file left beside it


# -- synthetic: the rasterizer and the skinning maths ---------------------------------------------
def test_rasterizer_nearest_wins_and_shared_edges_leave_no_gap():
    # a 40 x 30 pixel rectangle as two triangles sharing a diagonal: every pixel centre inside, once
    pixels = np.array([[10.0, 10.0], [50.0, 10.0], [50.0, 40.0], [10.0, 40.0]])
    quad = np.array([[0, 1, 2], [0, 2, 3]])
    fragments = rasterize(pixels, np.zeros(4), quad, (64, 48))
    ys, xs = np.divmod(fragments.index, 64)
    assert len(fragments.index) == 40 * 30 and xs.min() == 10 and xs.max() == 49 and ys.min() == 10 and ys.max() == 39
    assert np.allclose(fragments.barycentric.sum(axis=1), 1.0) and fragments.barycentric.min() >= 0
    assert coverage(pixels, quad, (64, 48)).sum() == 40 * 30
    # two overlapping triangles: the nearer one wins wherever they overlap, in either order
    tri = np.array([[0.0, 0.0], [60.0, 0.0], [0.0, 45.0]])
    both = np.concatenate([tri, tri + 5.0])
    for near_first in (True, False):
        depth = np.repeat([1.0, 0.0] if near_first else [0.0, 1.0], 3)
        frag = rasterize(both, depth, np.array([[0, 1, 2], [3, 4, 5]]), (64, 48))
        winner = frag.triangle[np.searchsorted(frag.index, 20 * 64 + 20)]
        assert winner == (0 if near_first else 1)
    # a triangle far off screen, and one with no area, draw nothing
    assert len(rasterize(np.array([[-90.0, -90.0], [-80.0, -90.0], [-90.0, -80.0]]), np.zeros(3), np.array([[0, 1, 2]]), (64, 48)).index) == 0
    assert len(rasterize(np.array([[1.0, 1.0], [30.0, 30.0], [60.0, 60.0]]), np.zeros(3), np.array([[0, 1, 2]]), (64, 48)).index) == 0


def _bar(weights_at_tip: float) -> SkinnedMesh:
    """A thin bar along +Y from 0 to 1 m bound to joint 0 (origin) and joint 1 (at y = 1)."""
    positions = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 1.0, 0.0], [0.1, 1.0, 0.0]])
    w = weights_at_tip
    weights = np.array([[1.0, 0.0], [1.0, 0.0], [1 - w, w], [1 - w, w]])
    inverse_bind = np.stack([np.eye(4), np.eye(4)])
    inverse_bind[1, :3, 3] = [0.0, -1.0, 0.0]  # joint 1 stands at y = 1 in the bind pose
    return SkinnedMesh("bar", positions, np.tile([0.0, 0.0, 1.0], (4, 1)), [[0, 1, 2], [1, 3, 2]],
                       np.tile([0, 1], (4, 1)), weights, [0, 1], inverse_bind, base_color=[1.0, 0.5, 0.2, 1.0])


def test_linear_blend_skinning_over_frames():
    mesh = _bar(1.0)
    quarter = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi / 2)  # +X turns to +Y
    rotations = np.stack([np.tile(quat.IDENTITY, (2, 1)), np.stack([quat.IDENTITY, quarter])])  # (F=2, J=2, 4)
    positions = np.array([[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    posed, normals = mesh.skin(rotations, positions)
    assert posed.shape == (2, 4, 3) and np.allclose(posed[0], mesh.positions, atol=1e-6)
    assert np.allclose(posed[1, 3], [0.0, 1.1, 0.0], atol=1e-6)  # the tip turned with joint 1
    assert np.allclose(posed[1, 1], [0.1, 0.0, 0.0], atol=1e-6)  # the base stayed with joint 0
    assert np.allclose(normals[1], [0.0, 0.0, 1.0], atol=1e-6)
    half = _bar(0.5).skin(rotations, positions)[0]
    assert np.allclose(half[1, 3], ([0.1, 1.0, 0.0] + np.array([0.0, 1.1, 0.0])) / 2, atol=1e-6)


def test_merge_shares_bones_and_keeps_colours():
    a, b = _bar(1.0), _bar(0.5)
    merged = merge([a, b])
    assert merged.num_vertices == 8 and merged.num_triangles == 4 and len(merged.bind_joints) == 2
    assert merged.triangles.max() == 7 and np.allclose(merged.colors, [1.0, 0.5, 0.2, 1.0])
    rot = np.tile(quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.3), (1, 2, 1))
    pos = np.array([[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    assert np.allclose(merged.skin(rot, pos)[0][0], np.concatenate([a.skin(rot, pos)[0][0], b.skin(rot, pos)[0][0]]), atol=1e-6)


def test_skinned_mesh_checks_its_arrays():
    mesh = _bar(1.0)
    with pytest.raises(ValueError, match="out of range"):
        SkinnedMesh("bad", mesh.positions, mesh.normals, [[0, 1, 9]], mesh.joints, mesh.weights, mesh.bind_joints, mesh.inverse_bind)
    with pytest.raises(ValueError, match="NaN"):
        SkinnedMesh("bad", np.full((4, 3), np.nan), mesh.normals, mesh.triangles, mesh.joints, mesh.weights,
                    mesh.bind_joints, mesh.inverse_bind)
    with pytest.raises(ValueError, match="bone out of range"):
        SkinnedMesh("bad", mesh.positions, mesh.normals, mesh.triangles, mesh.joints + 1, mesh.weights,
                    mesh.bind_joints, mesh.inverse_bind)


def test_meshopt_index_codecs_on_small_streams():
    from infuse_gltf import meshopt

    # a quad: three new vertices (code 0xfe, explicit byte 0: restart), then the last edge (0, 2) and a new vertex
    quad = bytes([0xE1, 0xFE, 0x00, 0x00]) + bytes(16)
    assert meshopt.decode_triangles(quad, 6).tolist() == [0, 1, 2, 0, 2, 3]
    # index sequence: deltas +0, +1, +1, +3, -1 against baseline 0 (zigzag, shifted past the baseline bit)
    sequence = bytes([0xD1, 0x00, 0x04, 0x04, 0x0C, 0x02]) + bytes(4)
    assert meshopt.decode_indices(sequence, 5).tolist() == [0, 1, 2, 5, 4]
    with pytest.raises(meshopt.MeshoptError, match="left over"):
        meshopt.decode_triangles(bytes([0xE1, 0xFE, 0x00, 0x00, 0x07]) + bytes(16), 3)
    # index data never stands for a skeleton or a clip
    with pytest.raises(meshopt.MeshoptUnsupported, match="mesh data"):
        meshopt.decode_view({"mode": "TRIANGLES", "count": 6, "byteStride": 2}, quad)
    assert np.frombuffer(meshopt.decode_view({"mode": "TRIANGLES", "count": 6, "byteStride": 2}, quad, mesh=True),
                         "<u2").tolist() == [0, 1, 2, 0, 2, 3]
