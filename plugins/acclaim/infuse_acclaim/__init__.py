"""Acclaim ASF skeletons and AMC motions (the CMU motion capture format) for infuse.

An ASF bone has a rest ``direction`` (world axes) and ``length``, and a local frame ``C`` given by
``axis`` angles. An AMC frame gives each bone's dof angles ``M``; the bone turns by ``C M C^-1``
relative to its parent. infuse puts one joint at the start (proximal end) of each bone, with
world-aligned rest frames, so a joint's local rotation is exactly ``C M C^-1`` and its rest offset
is its parent bone's ``direction * length``. Leaf bones end in end sites.
"""
