"""SmartBody ``.sk`` skeletons and ``.skm`` motions for infuse.

The readers reproduce what SmartBody computes for a joint: its local transform is the rotation
``prerot * value * postrot`` (``value`` is the Quat channel, or the Euler channels composed in the
joint's ``euler`` order) and the translation ``offset + position channels``, both in the parent's
frame. Position and Euler channels respect the joint's limits (a dof without a channel is frozen).
SmartBody is +Y up and +Z forward, the core frame, so only units are converted.
"""
