"""COLLADA 1.4/1.5 reader for infuse: joints, rest pose, skinned meshes, morph targets and animations."""
