"""glTF 2.0 (``.gltf``, ``.glb``), VRM 0.x / 1.0 (``.vrm``) and VRM Animation (``.vrma``) for infuse.

A json + numpy reader (:mod:`infuse_gltf.reader`) and a writer (:mod:`infuse_gltf.writer`) that copies
a character back with new clips and morph-weight tracks. See those modules for the conventions.
"""
from .container import GltfDocument, parse_bytes, parse_file
from .reader import read
from .writer import write


__all__ = ["GltfDocument", "parse_bytes", "parse_file", "read", "write"]
