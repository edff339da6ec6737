"""Toes kept off the ground stand where the pack's feet do: a pack without an idle takes the feet's
floor from its slowest walk, and Bandai dataset-1 masculinity's is its walk back, whose right toes are
bent up at foot flat (tip 10.3 cm up against 3.3 cm for the left). Both feet stand on one ground, so
both toes' tips stand at the lower height; before, Brad's right toes stayed curled up all the walk and
the heel joint hanging from them went 14.7 cm under the floor."""
from __future__ import annotations

import numpy as np

import infuse
from infuse.packs import build_pack, import_bvh_folder
from infuse.packs.infusion import as_character, infuse_character
from infuse.packs.walk_test import _runtime_walks

from corpus_data import corpus_file, require_corpus


def test_toes_bent_up_in_the_slowest_walk_do_not_stay_bent(tmp_path):
    require_corpus()
    data = corpus_file("bandai/Bandai-Namco-Research-Motiondataset-1/data")
    pack = import_bvh_folder(data, tmp_path / "pack", name="masculinity", pattern="dataset-1_*_masculinity_*.bvh")
    build_pack(pack)
    brad = as_character(infuse.load(corpus_file("smartbody/ChrBrad/ChrBrad.sk")))
    infusion = infuse_character(brad, [str(pack)])
    brad.mapping = infusion.mapping
    ((motion, (_, positions)),), _ = _runtime_walks(brad, infusion.mapping, next(iter(infusion.spaces.values())),
                                                   [dict(speed=1.3)], 4.5)
    index = motion.skeleton.index
    for side in ("Rt", "Lf"):
        toe, heel = positions[:, index[f"JtToe{side}"], 1], positions[:, index[f"JtHeel{side}"], 1]
        assert np.median(toe) < 0.06, (side, np.median(toe))  # 0.103 m on the right before
        assert heel.min() > -0.03, (side, heel.min())  # -0.147 m on the right before
