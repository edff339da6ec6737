"""Binary FBX reader for infuse: skeleton models, rest pose, animation stacks, blend-shape names."""
