"""COLLADA 1.4/1.5 reader for infuse: joints, rest pose, morph target names and animations."""
