"""The glb files infuse writes, opened in real Blender (its Python module ``bpy`` and glTF importer).

Writes outputs with the project's CLI from corpus characters into a temporary folder
(``retarget`` onto SmartBody's Brad keeping its own clips, and onto a VRM; ``speak`` with the Ready
Player Me avatar; ``batch`` onto Xbot; ``run`` of the quickstart scene, Xbot and the avatar), then
imports each glb into a fresh Blender scene (``bpy.ops.import_scene.gltf``) in the peer interpreter
``benchmarks/.blender-venv`` (made by ``benchmarks/setup_blender.sh``; bpy is never a dependency of
infuse) and prints one row per file:

- ``action``: the armature's active action in Blender (the importer makes the file's first
  animation active), and ``new clip``: whether it is the clip the command made;
- ``ground (mm)``: the lowest point of the deformed meshes at the clip's first frame, Blender's
  world Z (the ground), beside ``infuse (mm)``: the lowest point of the feet, soles included,
  in infuse's FK of the same frame (:func:`infuse.grounding.foot_height`);
- ``joint err (mm)``: the largest distance between Blender's posed bone heads (world) and infuse's
  FK of the written clip (read back with infuse's glTF reader) over ``--frames`` frames spread over
  the clip, joints matched by name; ``joints`` counts the matched ones.

infuse's core frame is +Y up, +Z forward; Blender's importer turns glTF's +Y up into +Z up:
(x, y, z) -> (x, -z, y). A VRM 0.x file that infuse turned 180° about +Y to face +Z is turned back
first (``Asset.facing_turned``). Blender plays a glTF time t at frame t × scene fps.

    benchmarks/setup_blender.sh
    .venv/bin/python benchmarks/blender_check.py [--frames 5] [--keep DIR]
"""
from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
BLENDER_PYTHON = HERE / ".blender-venv" / "bin" / "python"
CORPUS = Path(os.environ.get("INFUSE_CORPUS", REPO.parent / "shared" / "corpus")).resolve()

WALK = "bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh"
BRAD = "smartbody/mesh/brad/Brad.dae"
XBOT = "runxaway-models/Xbot.glb"
RPM = "talkinghead/avatars/brunette-t.glb"
VRM = "vrm-specification/samples/VRMC_vrm_expressions_isBinary_Overrides/vrm/VRMC_vrm_expressions_isBinary_Overrides.vrm"


def write_outputs(folder: Path) -> list[tuple[str, Path, str]]:
    """Run the CLI; return (command, glb, name of the clip it made) per output file."""
    infuse = [str(REPO / ".venv" / "bin" / "infuse")]
    for sub in ("cast", "mocap"):
        (folder / sub).mkdir()
    links = {"cast/Xbot.glb": XBOT, "mocap/walk.bvh": WALK, "Xbot.glb": XBOT, "avatar.glb": RPM}
    for name, source in links.items():
        (folder / name).symlink_to(CORPUS / source)
    quickstart = (REPO / "docs" / "quickstart.md").read_text(encoding="utf-8")
    (folder / "meeting.toml").write_text(re.findall(r"^```toml\n(.*?)^```", quickstart, flags=re.M | re.S)[0], encoding="utf-8")
    runs = [("retarget", ["retarget", str(CORPUS / WALK), "--to", str(CORPUS / BRAD), "-o", "brad.glb", "--keep-clips"]),
            ("retarget", ["retarget", str(CORPUS / WALK), "--to", str(CORPUS / VRM), "-o", "vrm.glb"]),
            ("speak", ["speak", "avatar.glb", "Hello there.", "-o", "hello.glb"]),
            ("batch", ["batch", "cast", "--motions", "mocap", "-o", "batch"]),
            ("run", ["run", "meeting.toml", "-o", "meeting"])]
    for _, argv in runs:
        subprocess.run(infuse + argv, cwd=folder, check=True, stdout=subprocess.DEVNULL)
    clip = Path(WALK).stem
    return [("retarget", folder / "brad.glb", clip), ("retarget", folder / "vrm.glb", clip),
            ("speak", folder / "hello.glb", "speech"), ("batch", folder / "batch" / "Xbot" / "walk.glb", "walk"),
            ("run", folder / "meeting" / "bob.glb", "scene"), ("run", folder / "meeting" / "ann.glb", "scene")]


def infuse_expectations(path: Path, clip: str, frames: int) -> dict:
    """infuse's FK of ``clip`` in ``path`` at ``frames`` times spread over it, in Blender's axes."""
    import numpy as np
    from infuse.fileio import load
    from infuse.contacts import feet
    from infuse.grounding import foot_height
    from infuse.kinematics import motion_fk
    from infuse.mapping import map_skeleton

    asset = load(path)
    motion = asset.motions[clip]
    picks = np.unique(np.linspace(0, motion.num_frames - 1, frames).round().astype(int))
    positions = motion_fk(motion)[1][picks]                          # (K, J, 3) core frame, metres
    if asset.facing_turned:
        positions = positions * np.array([-1.0, 1.0, -1.0])         # back to the file's -Z front
    blender = np.stack([positions[..., 0], -positions[..., 2], positions[..., 1]], axis=-1)
    mapping = map_skeleton(asset, meta=asset.meta)
    foot_joints = [asset.skeleton.names[j] for foot in feet(asset.skeleton, mapping, file=path) for j in foot.joints]
    first = motion.replace(local_rotations=motion.local_rotations[:1], root_translations=motion.root_translations[:1],
                           joint_translations=None if motion.joint_translations is None else motion.joint_translations[:1])
    return {"times": (picks / motion.fps).tolist(), "joints": list(asset.skeleton.names),
            "positions": blender.tolist(), "foot_height": foot_height(asset, mapping, first), "feet": foot_joints}


# Runs in the Blender venv: argv[1] is a JSON list of {file, clip, times, joints, positions};
# prints one JSON object per file.
BLENDER_SCRIPT = r"""
import json, sys
import bpy
import numpy as np

def world_points(objects, names, arm):
    # (N, 3) world positions of the joints: posed bone heads, or the node objects of a file without skin
    if arm is None:
        return np.array([objects[n].matrix_world.translation for n in names])
    world = np.array(arm.matrix_world)
    return np.array([arm.pose.bones[n].head for n in names]) @ world[:3, :3].T + world[:3, 3]


for job in json.loads(open(sys.argv[1]).read()):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.import_scene.gltf(filepath=job["file"])
    scene = bpy.context.scene
    fps = scene.render.fps / scene.render.fps_base
    rigs = [o for o in scene.objects if o.type == "ARMATURE"]
    arm = max(rigs, key=lambda o: len(o.data.bones)) if rigs else None
    objects = {o.name: o for o in scene.objects}
    names = [n for n in job["joints"] if (n in arm.pose.bones if arm else n in objects)]
    columns = [job["joints"].index(n) for n in names]
    expected = np.asarray(job["positions"])[:, columns]
    driver = arm if arm else objects[names[0]]
    action = driver.animation_data.action.name if driver.animation_data and driver.animation_data.action else None
    skinned = [o for o in scene.objects if o.type == "MESH" and arm is not None
               and any(m.type == "ARMATURE" and m.object == arm for m in o.modifiers)]
    def lowest():
        # lowest world Z of the deformed skinned meshes, and of the foot joints
        depsgraph = bpy.context.evaluated_depsgraph_get()
        lows = []
        for obj in skinned:
            ev = obj.evaluated_get(depsgraph)
            mesh = ev.to_mesh()
            co = np.empty(len(mesh.vertices) * 3)
            mesh.vertices.foreach_get("co", co)
            ev.to_mesh_clear()
            if len(co):
                m = np.array(ev.matrix_world)
                lows.append(float((co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3])[:, 2].min()))
        foot = [n for n in job["feet"] if n in names]
        return (min(lows) if lows else None), (float(world_points(objects, foot, arm)[:, 2].min()) if foot else None)

    got = []
    if arm is not None:
        arm.data.pose_position = "REST"
        scene.frame_set(0)
        rest = lowest()
        arm.data.pose_position = "POSE"
    else:
        rest = (None, None)
    for k, t in enumerate(job["times"]):
        frame = t * fps
        scene.frame_set(int(np.floor(frame)), subframe=float(frame - np.floor(frame)))
        got.append(world_points(objects, names, arm))
        if k == 0:
            first = lowest()
    err = float(np.linalg.norm(np.asarray(got) - expected, axis=-1).max()) if names else None
    print(json.dumps({"file": job["file"], "action": action, "object": driver.name, "ground": first[0],
                      "feet": first[1], "rest_ground": rest[0], "rest_feet": rest[1], "matched": len(names), "joints": len(job["joints"]), "error": err}))
"""


def mm(metres: float | None, digits: int = 1) -> str:
    """Metres as millimetres for the table; a dash when Blender has nothing to measure."""
    return "—" if metres is None else f"{metres * 1e3:.{digits}f}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=5, help="frames compared per clip (spread over it)")
    parser.add_argument("--keep", type=Path, help="write the outputs into this (new) folder and keep them")
    args = parser.parse_args(argv)
    if not BLENDER_PYTHON.exists():
        sys.exit(f"{BLENDER_PYTHON} missing: run benchmarks/setup_blender.sh first")
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.keep or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        outputs = write_outputs(folder)
        jobs = [{"file": str(path), "clip": clip, **infuse_expectations(path, clip, args.frames)} for _, path, clip in outputs]
        (folder / "jobs.json").write_text(json.dumps(jobs), encoding="utf-8")
        (folder / "blender_side.py").write_text(BLENDER_SCRIPT, encoding="utf-8")
        version = subprocess.run([str(BLENDER_PYTHON), "-c", "import bpy; print(bpy.app.version_string)"],
                                 capture_output=True, text=True, check=True).stdout.strip().splitlines()[-1]
        done = subprocess.run([str(BLENDER_PYTHON), str(folder / "blender_side.py"), str(folder / "jobs.json")],
                              capture_output=True, text=True)
        if done.returncode:
            sys.exit(f"Blender's side failed (exit {done.returncode}):\n{done.stderr[-3000:]}")
        rows = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    print(f"Blender {version}, {args.frames} frames per clip; heights in mm, Blender's world Z")
    print("| command | file | active action | new clip | ground | infuse | feet | rest ground | rest feet | joints | joint err (mm) |")
    print("|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for (command, path, clip), job, row in zip(outputs, jobs, rows):
        # Blender's importer names an action <animation>_<object> (the object it animates)
        new = row["action"] in (clip, f"{clip}_{row['object']}")
        print(f"| {command} | {path.relative_to(folder)} | {row['action']} | {'yes' if new else 'NO'} | {mm(row['ground'])} "
              f"| {mm(job['foot_height'])} | {mm(row['feet'])} | {mm(row['rest_ground'])} | {mm(row['rest_feet'])} "
              f"| {row['matched']}/{row['joints']} | {mm(row['error'], 2)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
