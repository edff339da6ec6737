"""Behaviour packs: manifest, builder, tessellation, importers (SmartBody, Bandai BVH), infusion and cache."""
from __future__ import annotations

import time

import numpy as np
import pytest

import infuse
from infuse.errors import InputError
from infuse.packs import (Tessellation, build_pack, import_bvh_folder, import_smartbody, infuse_character, installed_packs,
                          load_pack, read_manifest, summary)
from infuse.packs.manifest import write_manifest

from corpus_data import corpus_file, require_corpus

BUILT_IN = ("locomotion-male", "locomotion-female", "reaching")
BANDAI = "bandai/Bandai-Namco-Research-Motiondataset-1/data"


def test_built_in_packs_are_installed_and_built():
    table = installed_packs()
    for name in BUILT_IN:
        pack = load_pack(table[name].manifest)
        assert pack.built, name
        assert pack.analysis["report"] == [], pack.analysis["report"]
    male, female = load_pack("locomotion-male"), load_pack("locomotion-female")
    for pack in (male, female):
        roles = {c.name: c.role for c in pack.manifest.clips}
        assert len(roles) >= 8
        for name in ("idle", "walk_slow", "walk", "walk_fast", "jog", "run", "walk_turn_left", "walk_turn_right", "strafe_left"):
            assert name in roles


def test_locomotion_parameters_are_measured():
    pack = load_pack("locomotion-male")
    p = {c["name"]: c["parameters"] for c in pack.analysis["clips"]}
    assert p["idle"]["speed"] < 0.01
    speeds = [p[n]["speed"] for n in ("walk_slow", "walk", "walk_fast", "jog", "run")]
    assert speeds == sorted(speeds) and speeds[0] > 0.5 and speeds[-1] > 3.0
    assert np.degrees(p["walk_turn_left"]["turn_rate"]) == pytest.approx(50.0, abs=2.0)
    assert np.degrees(p["walk_turn_right"]["turn_rate"]) == pytest.approx(-50.0, abs=2.0)
    assert np.degrees(p["strafe_left"]["direction"]) == pytest.approx(90.0, abs=3.0)
    for c in pack.analysis["clips"]:
        if c["role"] == "cycle":
            feet = {s["foot"] for s in c["steps"]}
            assert feet == {"left", "right"}, c["name"]
            k = c["keys"]
            assert k[0] < k[1] < k[2]


def test_style_differences_between_packs():
    """Women: higher cadence, narrower steps, more pelvic obliquity (the pack README's figures)."""
    m, f = load_pack("locomotion-male"), load_pack("locomotion-female")
    cyc = lambda pack: [c for c in pack.analysis["clips"] if c["name"] == "walk"][0]["parameters"]["duration"]  # noqa: E731
    assert cyc(f) < cyc(m)  # shorter stride duration: higher cadence

    def step_width(pack):
        g = infuse.motion_fk(pack.motions["walk"])[1]
        ix = pack.mapping.indices(pack.skeleton)
        return float(np.mean(np.abs(g[:, ix["l_ankle"], 0] - g[:, ix["r_ankle"], 0])))

    assert step_width(f) < step_width(m) - 0.02


def test_tessellation_barycentric_weights_reproduce_points():
    rng = np.random.default_rng(1)
    for dims in (1, 2, 3):
        pts = rng.uniform(-1, 1, (12, dims))
        t = Tessellation.build([f"c{i}" for i in range(dims)], [str(i) for i in range(12)], pts)
        assert t.dimension == dims
        q = pts[:4].mean(axis=0, keepdims=True)
        w, inside = t.weights(q)
        assert inside[0] and w.sum() == pytest.approx(1.0)
        assert np.allclose(w @ pts, q, atol=1e-9)
        w, inside = t.weights(np.full((1, dims), 5.0))  # outside: the nearest hull point, flagged
        assert not inside[0] and np.all(w >= 0) and w.sum() == pytest.approx(1.0)
    flat = Tessellation.build(["a", "b", "c"], list("wxyz"), [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    assert flat.dimension == 2  # a plane in 3D is tessellated in 2D


def test_manifest_errors_name_the_key(tmp_path):
    write_manifest(tmp_path / "manifest.toml", {"name": "x", "version": "1", "kind": "dance", "skeleton": "s.bvh"},
                   [{"file": "a.bvh"}])
    with pytest.raises(InputError, match="pack.kind"):
        read_manifest(tmp_path)
    (tmp_path / "manifest.toml").write_text("[pack\n")
    with pytest.raises(InputError):
        read_manifest(tmp_path)


@pytest.fixture(scope="module")
def smartbody_packs(tmp_path_factory):
    require_corpus()
    out = {}
    for name in ("MaleLocomotion", "FemaleLocomotion"):
        dest = tmp_path_factory.mktemp(name)
        out[name] = build_pack(import_smartbody(corpus_file(f"smartbody/behaviorsets/{name}"), dest).parent)
    return out


def test_smartbody_behaviour_sets_import_and_tessellate(smartbody_packs):
    male = smartbody_packs["MaleLocomotion"]
    params = {c["name"]: c["parameters"] for c in male.analysis["clips"]}
    assert 1.2 < params["ChrUtah_Walk001"]["speed"] < 1.5
    assert params["ChrUtah_Run001"]["speed"] > params["ChrUtah_Jog001"]["speed"] > params["ChrUtah_Walk001"]["speed"]
    assert params["ChrUtah_WalkInCircleLeft001"]["turn_rate"] > 0.5 > -0.5 > params["ChrUtah_WalkInCircleRight001"]["turn_rate"]
    assert params["ChrUtah_StrafeSlowLf01"]["lateral_speed"] > 0.5 > -0.5 > params["ChrUtah_StrafeSlowRt01"]["lateral_speed"]
    t = male.tessellations()["locomotion"]
    assert t.dimension == 3 and len(t.simplices) > 10
    female = smartbody_packs["FemaleLocomotion"]
    tf = female.tessellations()["locomotion"]
    assert tf.dimension >= 2 and "Walk01" in tf.labels
    print(summary(male))
    print(summary(female))


@pytest.fixture(scope="module")
def bandai_packs(tmp_path_factory):
    require_corpus()
    out = {}
    for style in ("normal", "feminine", "masculinity"):
        dest = tmp_path_factory.mktemp(style)
        out[style] = build_pack(import_bvh_folder(corpus_file(BANDAI), dest, name=f"bandai-{style}", pattern=f"*_{style}_*.bvh").parent)
    return out


def test_bandai_style_folders_import_and_tessellate(bandai_packs):
    for style, pack in bandai_packs.items():
        p = {c["name"]: c["parameters"] for c in pack.analysis["clips"]}
        walk = p[f"dataset-1_walk_{style}_001"]["speed"]
        run = p[f"dataset-1_run_{style}_001"]["speed"]
        dash = p[f"dataset-1_dash_{style}_001"]["speed"]
        assert 0.5 < walk < run < dash, (style, walk, run, dash)
        left = p[f"dataset-1_walk-left_{style}_001"]["lateral_speed"]
        right = p[f"dataset-1_walk-right_{style}_001"]["lateral_speed"]
        back = p[f"dataset-1_walk-back_{style}_001"]["forward_speed"]
        assert left > 0.1 and right < -0.1 and back < -0.3, (style, left, right, back)
        t = pack.tessellations()["locomotion"]
        assert t.dimension >= 2
        print(summary(pack))


def test_imported_packs_infuse_and_blend(bandai_packs, smartbody_packs):
    xbot = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    infusion = infuse_character(xbot, [bandai_packs["feminine"], smartbody_packs["MaleLocomotion"]])
    for space in infusion.spaces.values():
        t = space.tessellations["locomotion"]
        order = np.argsort(t.points[:, 0])
        query = 0.5 * (t.points[order[-1]] + t.points[order[len(order) // 2]])  # between two examples: inside the hull
        w, inside = space.weights("locomotion", [query])
        assert inside[0] and w.sum() == pytest.approx(1.0) and (w > 1e-6).sum() >= 2
        assert np.allclose(w @ t.points, query, atol=1e-6)


def test_infusion_cache_is_reused(tmp_path):
    require_corpus()
    xbot = infuse.load(corpus_file("runxaway-models/Xbot.glb"))
    assert xbot.skeleton.num_joints == 65
    first = infuse_character(xbot, list(BUILT_IN), cache=tmp_path)
    assert not first.cached and first.cache_file.is_file()
    start = time.perf_counter()
    second = infuse_character(xbot, list(BUILT_IN), cache=tmp_path)
    assert second.cached and time.perf_counter() - start < first.seconds
    for name in BUILT_IN:
        a, b = first.spaces[name], second.spaces[name]
        assert list(a.clips) == list(b.clips)
        for clip in a.clips:
            assert np.allclose(a.clips[clip].motion.local_rotations, b.clips[clip].motion.local_rotations)
        assert np.allclose(a.tessellations[next(iter(a.tessellations))].points, b.tessellations[next(iter(b.tessellations))].points)
