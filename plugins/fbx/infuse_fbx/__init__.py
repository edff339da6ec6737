"""FBX reader (binary and ASCII 7.x, pure Python) for infuse: skeleton models, rest pose, animation stacks,
blend-shape names, and skinned meshes with their materials."""
