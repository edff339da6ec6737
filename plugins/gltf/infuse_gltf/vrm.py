"""VRM 0.x, VRM 1.0 and VRM Animation (VRMA) extensions: humanoid bone maps and expressions.

- VRM 0.x: ``extensions.VRM`` (``humanoid.humanBones`` is a list of ``{bone, node}``; expressions are
  ``blendShapeMaster.blendShapeGroups`` with ``binds`` ``{mesh, index, weight 0..100}``). Its models
  face -Z (UniVRM flips X when exporting from Unity).
- VRM 1.0: ``extensions.VRMC_vrm`` (``humanoid.humanBones`` maps bone -> ``{node}``; expressions are
  ``expressions.preset`` / ``expressions.custom`` with ``morphTargetBinds`` ``{node, index, weight 0..1}``).
  Its models face +Z like glTF.
- VRMA: ``extensions.VRMC_vrm_animation`` (``humanoid.humanBones`` like VRM 1.0; each expression is a
  node whose animated ``translation.x`` is the weight; ``lookAt.node`` is a gaze target).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from infuse.errors import InputError

from .accessors import check_index


#: VRM 1.0 preset expression names (others are custom expressions).
VRM_PRESET_EXPRESSIONS = ("happy", "angry", "sad", "relaxed", "surprised", "aa", "ih", "ou", "ee", "oh", "blink",
                          "blinkLeft", "blinkRight", "lookUp", "lookDown", "lookLeft", "lookRight", "neutral")


@dataclass
class Expression:
    """One VRM expression: its name and the morph targets it drives.

    ``binds`` holds ``(kind, index, target, weight)`` with kind ``"node"`` (VRM 1.0, a mesh node) or
    ``"mesh"`` (VRM 0.x), ``target`` the morph target index and ``weight`` in 0..1. ``node`` is the
    VRMA expression node (its translation.x carries the weight), else ``None``.
    """

    name: str
    binds: list = field(default_factory=list)
    node: int | None = None


@dataclass
class VrmInfo:
    """What the VRM extensions say: ``version`` ("0.x", "1.0" or "vrma-1.0"), ``bones`` (VRM bone name ->
    node index), ``expressions`` in file order, and ``look_at_node`` (VRMA gaze target node)."""

    version: str
    bones: dict[str, int]
    expressions: list[Expression]
    look_at_node: int | None = None

    @property
    def expression_nodes(self) -> set[int]:
        return {e.node for e in self.expressions if e.node is not None}


def _obj(value) -> dict:
    return value if isinstance(value, dict) else {}


def _arr(value) -> list:
    return value if isinstance(value, list) else []


def _bind(file, place: str, bind, ref_key: str, default_weight: float) -> tuple:
    """``(ref, target index, weight)`` of one morph target bind, or :class:`InputError`."""
    if not isinstance(bind, dict):
        raise InputError(file, place, "is not an object")
    ref, index, weight = bind.get(ref_key), bind.get("index"), bind.get("weight", default_weight)
    if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in (ref, index)):
        raise InputError(file, place, f"{ref_key} and index must be non-negative integers")
    if not isinstance(weight, (int, float)) or isinstance(weight, bool) or not float(weight) == float(weight):
        raise InputError(file, place, "weight is not a number")
    return ref, index, float(weight)


def vrm_info(doc_json: dict, file) -> VrmInfo | None:
    """The VRM facts of a document, or ``None`` for a plain glTF."""
    ext = doc_json.get("extensions") or {}
    n_nodes = len(doc_json.get("nodes", []))
    if not isinstance(ext, dict):
        return None
    if isinstance(ext.get("VRMC_vrm_animation"), dict):
        e = ext["VRMC_vrm_animation"]
        bones = _bones_v1(e, n_nodes, file, "extensions.VRMC_vrm_animation")
        exprs = []
        for group in ("preset", "custom"):
            for name, spec in _obj(_obj(e.get("expressions")).get(group)).items():
                if isinstance(spec, dict) and "node" in spec:
                    node = check_index(file, f"extensions.VRMC_vrm_animation.expressions.{group}.{name}", spec["node"], n_nodes, "node")
                    exprs.append(Expression(str(name), node=node))
        look = _obj(e.get("lookAt")).get("node")
        if look is not None:
            look = check_index(file, "extensions.VRMC_vrm_animation.lookAt", look, n_nodes, "node")
        return VrmInfo("vrma-1.0", bones, exprs, look)
    if isinstance(ext.get("VRMC_vrm"), dict):
        e = ext["VRMC_vrm"]
        bones = _bones_v1(e, n_nodes, file, "extensions.VRMC_vrm")
        exprs = []
        for group in ("preset", "custom"):
            for name, spec in _obj(_obj(e.get("expressions")).get(group)).items():
                place = f"extensions.VRMC_vrm.expressions.{group}.{name}.morphTargetBinds"
                binds = [("node",) + _bind(file, f"{place}[{k}]", b, "node", 1.0)
                         for k, b in enumerate(_arr(_obj(spec).get("morphTargetBinds")))]
                exprs.append(Expression(str(name), binds))
        return VrmInfo("1.0", bones, exprs)
    if isinstance(ext.get("VRM"), dict):
        e = ext["VRM"]
        bones: dict[str, int] = {}
        for k, b in enumerate(_arr(_obj(e.get("humanoid")).get("humanBones"))):
            if isinstance(b, dict) and "bone" in b and b.get("node") is not None and b.get("node") != -1:
                bones[str(b["bone"])] = check_index(file, f"extensions.VRM.humanoid.humanBones[{k}]", b["node"], n_nodes, "node")
        exprs = []
        for gi, g in enumerate(_arr(_obj(e.get("blendShapeMaster")).get("blendShapeGroups"))):
            if not isinstance(g, dict):
                continue
            preset = str(g.get("presetName") or "unknown")
            name = preset if preset != "unknown" else str(g.get("name") or f"expression{len(exprs)}")
            place = f"extensions.VRM.blendShapeMaster.blendShapeGroups[{gi}].binds"
            binds = []
            for k, b in enumerate(_arr(g.get("binds"))):
                mesh, index, weight = _bind(file, f"{place}[{k}]", b, "mesh", 100.0)
                binds.append(("mesh", mesh, index, weight / 100.0))
            exprs.append(Expression(name, binds))
        return VrmInfo("0.x", bones, exprs)
    return None


def _bones_v1(ext: dict, n_nodes: int, file, place: str) -> dict[str, int]:
    bones: dict[str, int] = {}
    human = _obj(ext.get("humanoid")).get("humanBones") or {}
    if not isinstance(human, dict):
        raise InputError(file, f"{place}.humanoid.humanBones", "is not an object")
    for bone, spec in human.items():
        if isinstance(spec, dict) and "node" in spec:
            bones[str(bone)] = check_index(file, f"{place}.humanoid.humanBones.{bone}", spec["node"], n_nodes, "node")
    return bones
