"""Morph target (blend shape) names of glTF meshes.

glTF has no field for them; exporters use ``mesh.extras.targetNames`` (Blender, three.js, Ready Player
Me), ``primitive.extras.targetNames``, or name the targets' POSITION accessors. Targets that none of
these name are called ``"<mesh name>.<k>"`` (``"mesh<m>.<k>"`` for an unnamed mesh).
"""
from __future__ import annotations


def _obj(value) -> dict:
    return value if isinstance(value, dict) else {}


def target_count(mesh: dict) -> int:
    """Number of morph targets of a mesh (every primitive must have the same number)."""
    prims = mesh.get("primitives")
    if not isinstance(prims, list) or not prims or not isinstance(prims[0], dict):
        return 0
    targets = prims[0].get("targets")
    return len(targets) if isinstance(targets, list) else 0


def mesh_target_names(doc_json: dict) -> list[list[str]]:
    """Morph target names of every mesh, in file order (an empty list for a mesh without targets)."""
    accessors = doc_json.get("accessors") or []
    out: list[list[str]] = []
    for m, mesh in enumerate(doc_json.get("meshes") or []):
        if not isinstance(mesh, dict):
            out.append([])
            continue
        n = target_count(mesh)
        prims = mesh.get("primitives")
        prim = prims[0] if isinstance(prims, list) and prims and isinstance(prims[0], dict) else {}
        candidates = [_obj(mesh.get("extras")).get("targetNames"), _obj(prim.get("extras")).get("targetNames")]
        names = next((list(map(str, c)) for c in candidates if isinstance(c, list) and len(c) == n), None)
        if names is None:
            acc_names = []
            targets = prim.get("targets")
            for target in targets if isinstance(targets, list) else []:
                idx = target.get("POSITION") if isinstance(target, dict) else None
                acc = accessors[idx] if isinstance(idx, int) and 0 <= idx < len(accessors) else {}
                acc_names.append(acc.get("name") if isinstance(acc, dict) else None)
            if all(isinstance(a, str) and a for a in acc_names) and len(set(acc_names)) == n:
                names = acc_names
        if names is None:
            base = mesh.get("name") or f"mesh{m}"
            names = [f"{base}.{k}" for k in range(n)]
        out.append(names)
    return out


def unique_in_order(groups) -> list[str]:
    """All names of ``groups`` (iterables of names), first occurrence order, without repeats."""
    seen: dict[str, None] = {}
    for g in groups:
        for name in g:
            seen.setdefault(name, None)
    return list(seen)
