"""infuse.transforms.nearest_joint_parents: joint parents across non-joint nodes, and the nodes skipped."""
from __future__ import annotations

import numpy as np

from infuse.transforms import nearest_joint_parents

#: 0 scene root, 1 armature (not a joint), 2 hips, 3 a non-joint pivot, 4 spine, 5 a prop under the
#: pivot (not a joint, no joint below), 6 a second armature, 7 its joint, 8 a leaf joint under the hips.
NODE_PARENTS = [-1, 0, 1, 2, 3, 3, -1, 6, 2]
JOINTS = [2, 4, 7, 8]


def test_parents_skip_non_joint_nodes():
    parents = nearest_joint_parents(NODE_PARENTS, JOINTS)
    assert parents.dtype == np.int64
    assert parents.tolist() == [-1, 0, -1, 0]  # spine (4) hangs from hips (2) across the pivot (3)


def test_folded_nodes_are_every_non_joint_ancestor():
    parents, folded = nearest_joint_parents(np.array(NODE_PARENTS), JOINTS, return_folded=True)
    assert parents.tolist() == nearest_joint_parents(NODE_PARENTS, JOINTS).tolist()
    assert folded.tolist() == [0, 1, 3, 6]  # the prop (5) is no joint's ancestor
    reference = set()
    for n in JOINTS:  # the plain walk from every joint to its scene root
        p = NODE_PARENTS[n]
        while p >= 0:
            reference.add(p)
            p = NODE_PARENTS[p]
    assert set(folded.tolist()) == reference - set(JOINTS)


def test_no_joints():
    parents, folded = nearest_joint_parents(NODE_PARENTS, [], return_folded=True)
    assert parents.shape == (0,) and folded.shape == (0,)
