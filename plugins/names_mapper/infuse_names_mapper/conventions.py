"""Joint names of well-known rigs, written as templates per canonical joint.

Placeholders: ``{Side}`` Left/Right, ``{side}`` left/right, ``{L}`` L/R, ``{l}`` l/r, ``{Lf}`` Lf/Rt,
``{n}`` a segment number. Group keys ``torso`` and ``neck`` list every torso or neck joint of a
rig, bottom-up; the labelling rule (chest = spine3, ...) turns them into spine1..spine5 once the
joints present are known. Names are compared after :func:`.match.normalize` (lower case, no
separators, no namespace), so ``mixamorig:LeftArm`` and ``Left_Arm`` both match ``LeftArm``.
"""
from __future__ import annotations

FINGERS = ("thumb", "index", "middle", "ring", "pinky")


def _fingers(template: dict[str, str], numbers: dict[str, tuple] | None = None) -> dict[str, list[str]]:
    """``{finger: "...{n}..."}`` -> per canonical finger joint (side-templated)."""
    out: dict[str, list[str]] = {}
    for finger, pattern in template.items():
        nums = (numbers or {}).get(finger, (1, 2, 3, 4))
        for seg, n in enumerate(nums, start=1):
            if n is not None:
                out.setdefault(f"{{s}}_{finger}{seg}", []).append(pattern.replace("{n}", str(n)))
    return out


def _merge(*parts: dict[str, list[str]]) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for part in parts:
        for k, v in part.items():
            out.setdefault(k, []).extend(v)
    return out


MIXAMO = _merge({
    "base": ["Hips"],
    "torso": ["Spine", "Spine1", "Spine2", "Spine3"],
    "neck": ["Neck", "Neck1", "Neck2"],
    "skullbase": ["Head"],
    "eyeball_{side}": ["{Side}Eye"],
    "{s}_acromioclavicular": ["{Side}Shoulder"],
    "{s}_shoulder": ["{Side}Arm"],
    "{s}_elbow": ["{Side}ForeArm"],
    "{s}_forearm": ["{Side}ForeArmRoll", "{Side}ForeArmTwist"],
    "{s}_wrist": ["{Side}Hand"],
    "{s}_hip": ["{Side}UpLeg"],
    "{s}_knee": ["{Side}Leg"],
    "{s}_ankle": ["{Side}Foot"],
    "{s}_forefoot": ["{Side}ToeBase"],
    "{s}_toe": ["{Side}Toe_End", "{Side}ToeBase_End", "{Side}FootToeBase_End"],
}, _fingers({f: "{Side}Hand" + f.capitalize() + "{n}" for f in FINGERS}))

UNREAL = _merge({
    "base": ["pelvis"],
    "torso": ["spine_01", "spine_02", "spine_03", "spine_04", "spine_05"],
    "neck": ["neck_01", "neck_02"],
    "skullbase": ["head"],
    "eyeball_{side}": ["eye_{l}", "FACIAL_{L}_Eye"],
    "{s}_acromioclavicular": ["clavicle_{l}"],
    "{s}_shoulder": ["upperarm_{l}"],
    "{s}_elbow": ["lowerarm_{l}"],
    "{s}_forearm": ["lowerarm_twist_01_{l}"],
    "{s}_wrist": ["hand_{l}"],
    "{s}_hip": ["thigh_{l}"],
    "{s}_knee": ["calf_{l}"],
    "{s}_ankle": ["foot_{l}"],
    "{s}_forefoot": ["ball_{l}"],
}, _fingers({f: f + "_0{n}_{l}" for f in FINGERS}, {f: (1, 2, 3, None) for f in FINGERS}))

#: VRM humanoid bone names (VRM 1.0; 0.x differs only for the thumb, see ``VRM0_THUMB``).
VRM = _merge({
    "base": ["hips"],
    "torso": ["spine", "chest", "upperChest"],
    "neck": ["neck"],
    "skullbase": ["head"],
    "eyeball_{side}": ["{side}Eye"],
    "{s}_acromioclavicular": ["{side}Shoulder"],
    "{s}_shoulder": ["{side}UpperArm"],
    "{s}_elbow": ["{side}LowerArm"],
    "{s}_wrist": ["{side}Hand"],
    "{s}_hip": ["{side}UpperLeg"],
    "{s}_knee": ["{side}LowerLeg"],
    "{s}_ankle": ["{side}Foot"],
    "{s}_forefoot": ["{side}Toes"],
    "{s}_thumb1": ["{side}ThumbMetacarpal"],
    "{s}_thumb2": ["{side}ThumbProximal"],
    "{s}_thumb3": ["{side}ThumbDistal"],
}, *({f"{{s}}_{c}{i}": [f"{{side}}{v}{seg}"]} for c, v in (("index", "Index"), ("middle", "Middle"),
                                                        ("ring", "Ring"), ("pinky", "Little"))
     for i, seg in ((1, "Proximal"), (2, "Intermediate"), (3, "Distal"))))
VRM0_THUMB = {"{s}_thumb1": ["{side}ThumbProximal"], "{s}_thumb2": ["{side}ThumbIntermediate"],
              "{s}_thumb3": ["{side}ThumbDistal"]}

#: VRoid Studio's own joint names (J_Bip_*), the rig most VRM files carry.
VROID = _merge({
    "base": ["J_Bip_C_Hips"],
    "torso": ["J_Bip_C_Spine", "J_Bip_C_Chest", "J_Bip_C_UpperChest"],
    "neck": ["J_Bip_C_Neck"],
    "skullbase": ["J_Bip_C_Head"],
    "eyeball_{side}": ["J_Adj_{L}_FaceEye"],
    "{s}_acromioclavicular": ["J_Bip_{L}_Shoulder"],
    "{s}_shoulder": ["J_Bip_{L}_UpperArm"],
    "{s}_elbow": ["J_Bip_{L}_LowerArm"],
    "{s}_wrist": ["J_Bip_{L}_Hand"],
    "{s}_hip": ["J_Bip_{L}_UpperLeg"],
    "{s}_knee": ["J_Bip_{L}_LowerLeg"],
    "{s}_ankle": ["J_Bip_{L}_Foot"],
    "{s}_forefoot": ["J_Bip_{L}_ToeBase"],
}, _fingers({"thumb": "J_Bip_{L}_Thumb{n}", "index": "J_Bip_{L}_Index{n}", "middle": "J_Bip_{L}_Middle{n}",
             "ring": "J_Bip_{L}_Ring{n}", "pinky": "J_Bip_{L}_Little{n}"}, {f: (1, 2, 3, None) for f in FINGERS}))

#: 3ds Max Biped ("Bip01" or "Bip001"; the normalizer folds both to "bip").
BIPED = _merge({
    "base": ["Bip01 Pelvis"],
    "torso": ["Bip01 Spine", "Bip01 Spine1", "Bip01 Spine2", "Bip01 Spine3"],
    "neck": ["Bip01 Neck", "Bip01 Neck1"],
    "skullbase": ["Bip01 Head"],
    "{s}_acromioclavicular": ["Bip01 {L} Clavicle"],
    "{s}_shoulder": ["Bip01 {L} UpperArm"],
    "{s}_elbow": ["Bip01 {L} Forearm"],
    "{s}_forearm": ["Bip01 {L} ForeTwist", "Bip01 {L} ForeTwist1"],
    "{s}_wrist": ["Bip01 {L} Hand"],
    "{s}_hip": ["Bip01 {L} Thigh"],
    "{s}_knee": ["Bip01 {L} Calf"],
    "{s}_ankle": ["Bip01 {L} Foot"],
    "{s}_forefoot": ["Bip01 {L} Toe0"],
    "{s}_toe": ["Bip01 {L} Toe01"],
}, *({f"{{s}}_{f}{seg}": [f"Bip01 {{L}} Finger{d}{suffix}"]}
     for d, f in enumerate(FINGERS) for seg, suffix in ((1, ""), (2, "1"), (3, "2"))))

#: CMU motion capture: the amc2bvh names, the Acclaim bone names and the "3ds Max friendly" release.
CMU_BVH = {
    "base": ["Hips"],
    "torso": ["LowerBack", "Spine", "Spine1"],
    "neck": ["Neck", "Neck1"],
    "skullbase": ["Head"],
    "{s}_acromioclavicular": ["{Side}Shoulder"],
    "{s}_shoulder": ["{Side}Arm"],
    "{s}_elbow": ["{Side}ForeArm"],
    "{s}_wrist": ["{Side}Hand"],
    "{s}_thumb1": ["{L}Thumb"],
    "{s}_index1": ["{Side}HandIndex1"],
    "{s}_hip": ["{Side}UpLeg"],
    "{s}_knee": ["{Side}Leg"],
    "{s}_ankle": ["{Side}Foot"],
    "{s}_forefoot": ["{Side}ToeBase"],
}
CMU_ASF = {
    "base": ["root"],
    "torso": ["lowerback", "upperback", "thorax"],
    "neck": ["lowerneck", "upperneck"],
    "skullbase": ["head"],
    "{s}_acromioclavicular": ["{l}clavicle"],
    "{s}_shoulder": ["{l}humerus"],
    "{s}_elbow": ["{l}radius"],
    "{s}_wrist": ["{l}wrist"],
    "{s}_thumb1": ["{l}thumb"],
    "{s}_hip": ["{l}femur"],
    "{s}_knee": ["{l}tibia"],
    "{s}_ankle": ["{l}foot"],
    "{s}_forefoot": ["{l}toes"],
}
CMU_3DSMAX = {
    "base": ["Hips"],
    "torso": ["lowerback", "Chest", "Chest2"],
    "neck": ["lowerneck", "Neck"],
    "skullbase": ["Head"],
    "{s}_acromioclavicular": ["{Side}Collar"],
    "{s}_shoulder": ["{Side}Shoulder"],
    "{s}_elbow": ["{Side}Elbow"],
    "{s}_wrist": ["{Side}Wrist"],
    "{s}_thumb1": ["{L}Thumb"],
    "{s}_hip": ["{Side}Hip"],
    "{s}_knee": ["{Side}Knee"],
    "{s}_ankle": ["{Side}Ankle"],
    "{s}_forefoot": ["{Side}Toe"],
}

#: SmartBody's own skeleton (the canonical names) and the ICT "zebra2" rigs (Jt names).
SMARTBODY_NAMES = ("base", "spine1", "spine2", "spine3", "spine4", "spine5", "skullbase", "eyeball_left",
                   "eyeball_right")
SMARTBODY = _merge({
    "base": ["base"],
    "spine1": ["spine1"], "spine2": ["spine2"], "spine3": ["spine3"], "spine4": ["spine4"], "spine5": ["spine5"],
    "skullbase": ["skullbase"],
    "eyeball_{side}": ["eyeball_{side}"],
    "upper_eyelid_{side}": ["upper_eyelid_{side}"],
    "lower_eyelid_{side}": ["lower_eyelid_{side}"],
}, {f"{{s}}_{j}": [f"{{l}}_{j}"] for j in ("sternoclavicular", "acromioclavicular", "shoulder", "elbow", "forearm",
                                             "wrist", "hip", "knee", "ankle", "forefoot", "toe")},
    _fingers({f: "{l}_" + f + "{n}" for f in FINGERS}))
ZEBRA2 = _merge({
    "base": ["JtRoot"],
    "torso": ["JtSpineA", "JtSpineB", "JtSpineC"],
    "neck": ["JtNeckA", "JtNeckB"],
    "skullbase": ["JtSkullA"],
    "eyeball_{side}": ["JtEye{Lf}"],
    "upper_eyelid_{side}": ["JtEyelidUpper{Lf}"],
    "lower_eyelid_{side}": ["JtEyelidLower{Lf}"],
    "{s}_acromioclavicular": ["JtClavicle{Lf}"],
    "{s}_shoulder": ["JtShoulder{Lf}"],
    "{s}_elbow": ["JtElbow{Lf}"],
    "{s}_forearm": ["JtForearmTwistA{Lf}"],
    "{s}_wrist": ["JtWrist{Lf}"],
    "{s}_hip": ["JtHip{Lf}"],
    "{s}_knee": ["JtKnee{Lf}"],
    "{s}_ankle": ["JtAnkle{Lf}"],
    "{s}_forefoot": ["JtBall{Lf}"],
    "{s}_toe": ["JtToe{Lf}"],
}, *({f"{{s}}_{f}{i}": [f"Jt{v}{letter}{{Lf}}"]} for f, v in (("thumb", "Thumb"), ("index", "Index"),
                                                             ("middle", "Middle"), ("ring", "Ring"), ("pinky", "Little"))
     for i, letter in enumerate("ABCD", start=1)))

#: Daz Studio: the "friendly" names of older figures and Genesis 3/8 names.
DAZ = _merge({
    "base": ["hip"],
    "torso": ["abdomenLower", "abdomen", "abdomenUpper", "abdomen2", "chestLower", "chest", "chestUpper"],
    "neck": ["neckLower", "neck", "neckUpper"],
    "skullbase": ["head"],
    "eyeball_{side}": ["{l}Eye"],
    "{s}_acromioclavicular": ["{l}Collar"],
    "{s}_shoulder": ["{l}Shldr", "{l}ShldrBend"],
    "{s}_elbow": ["{l}ForeArm", "{l}ForearmBend"],
    "{s}_forearm": ["{l}ForearmTwist"],
    "{s}_wrist": ["{l}Hand"],
    "{s}_hip": ["{l}Thigh", "{l}ThighBend"],
    "{s}_knee": ["{l}Shin"],
    "{s}_ankle": ["{l}Foot"],
    "{s}_forefoot": ["{l}Toe"],
}, _fingers({"thumb": "{l}Thumb{n}", "index": "{l}Index{n}", "middle": "{l}Mid{n}", "ring": "{l}Ring{n}",
             "pinky": "{l}Pinky{n}"}, {f: (1, 2, 3, None) for f in FINGERS}))

#: MakeHuman's default skeleton.
MAKEHUMAN = _merge({
    "base": ["root"],
    "torso": ["spine05", "spine04", "spine03", "spine02", "spine01"],
    "neck": ["neck01", "neck02", "neck03"],
    "skullbase": ["head"],
    "eyeball_{side}": ["eye.{L}"],
    "{s}_acromioclavicular": ["clavicle.{L}"],
    "{s}_shoulder": ["upperarm01.{L}"],
    "{s}_elbow": ["lowerarm01.{L}"],
    "{s}_forearm": ["lowerarm02.{L}"],
    "{s}_wrist": ["wrist.{L}"],
    "{s}_hip": ["upperleg01.{L}"],
    "{s}_knee": ["lowerleg01.{L}"],
    "{s}_ankle": ["foot.{L}"],
    "{s}_forefoot": ["toe1-1.{L}"],
}, *({f"{{s}}_{f}{seg}": [f"finger{d}-{seg}.{{L}}"]} for d, f in enumerate(FINGERS, start=1) for seg in (1, 2, 3)))

#: Blender Rigify deform bones (with or without the DEF- prefix).
RIGIFY = _merge({
    "base": ["DEF-spine"],
    "torso": ["DEF-spine.001", "DEF-spine.002", "DEF-spine.003"],
    "neck": ["DEF-spine.004", "DEF-spine.005"],
    "skullbase": ["DEF-spine.006"],
    "eyeball_{side}": ["ORG-eye.{L}", "DEF-eye.{L}"],
    "{s}_acromioclavicular": ["DEF-shoulder.{L}"],
    "{s}_shoulder": ["DEF-upper_arm.{L}"],
    "{s}_elbow": ["DEF-forearm.{L}"],
    "{s}_forearm": ["DEF-forearm.{L}.001"],
    "{s}_wrist": ["DEF-hand.{L}"],
    "{s}_hip": ["DEF-thigh.{L}"],
    "{s}_knee": ["DEF-shin.{L}"],
    "{s}_ankle": ["DEF-foot.{L}"],
    "{s}_forefoot": ["DEF-toe.{L}"],
}, *({f"{{s}}_{f}{seg}": [f"DEF-{v}.0{seg}.{{L}}"]} for f, v in (("thumb", "thumb"), ("index", "f_index"),
                                                                 ("middle", "f_middle"), ("ring", "f_ring"),
                                                                 ("pinky", "f_pinky")) for seg in (1, 2, 3)))

#: Plain English names with a side suffix (``UpperArm_L``, ``UpperArm.L``), common in game and
#: motion-capture exports (Bandai Namco's dataset, many Blender rigs).
GENERIC = _merge({
    "base": ["Hips", "Pelvis"],
    "torso": ["Spine", "Spine1", "Spine2", "Chest", "UpperChest"],
    "neck": ["Neck"],
    "skullbase": ["Head"],
    "eyeball_{side}": ["Eye_{L}", "Eye.{L}"],
    "{s}_acromioclavicular": ["Shoulder_{L}", "Shoulder.{L}", "Clavicle_{L}", "Clavicle.{L}"],
    "{s}_shoulder": ["UpperArm_{L}", "UpperArm.{L}", "Arm_{L}", "Arm.{L}"],
    "{s}_elbow": ["LowerArm_{L}", "LowerArm.{L}", "ForeArm_{L}", "ForeArm.{L}"],
    "{s}_wrist": ["Hand_{L}", "Hand.{L}"],
    "{s}_hip": ["UpperLeg_{L}", "UpperLeg.{L}", "Thigh_{L}", "Thigh.{L}"],
    "{s}_knee": ["LowerLeg_{L}", "LowerLeg.{L}", "Shin_{L}", "Shin.{L}", "Calf_{L}", "Calf.{L}"],
    "{s}_ankle": ["Foot_{L}", "Foot.{L}"],
    "{s}_forefoot": ["Toes_{L}", "Toes.{L}", "Toe_{L}", "Toe.{L}", "ToeBase_{L}", "ToeBase.{L}"],
})

#: Every convention by name, most specific first (ties go to the earlier one).
CONVENTIONS: dict[str, dict[str, list[str]]] = {
    "smartbody": SMARTBODY,
    "zebra2": ZEBRA2,
    "biped": BIPED,
    "unreal": UNREAL,
    "vroid": VROID,
    "vrm": VRM,
    "rigify": RIGIFY,
    "makehuman": MAKEHUMAN,
    "cmu-asf": CMU_ASF,
    "cmu-3dsmax": CMU_3DSMAX,
    "cmu": CMU_BVH,
    "daz": DAZ,
    "mixamo": MIXAMO,
    "generic": GENERIC,
}
