"""A pack manifest names only files in its own folder: a downloaded pack cannot read other local files."""
from __future__ import annotations

import pytest

from infuse.errors import ExternalReferenceError
from infuse.packs import read_manifest
from infuse.references import allow_external

MANIFEST = """[pack]
name = "p"
version = "0.1.0"
kind = "reach"
skeleton = "{skeleton}"

[[clips]]
name = "a"
file = "{clip}"
role = "reach"
hand = "left"
"""


def _write(folder, skeleton="skeleton.bvh", clip="clips/a.bvh"):
    (folder / "clips").mkdir(parents=True, exist_ok=True)
    path = folder / "manifest.toml"
    path.write_text(MANIFEST.format(skeleton=skeleton, clip=clip))
    return path


def test_files_inside_the_pack_folder_are_read(tmp_path):
    manifest = read_manifest(_write(tmp_path))
    assert manifest.clips[0].file == (tmp_path / "clips" / "a.bvh").resolve()


@pytest.mark.parametrize("clip, problem", [("../outside.bvh", "leads out of"), ("/etc/hostname", "absolute path"),
                                           ("clips/../../x.bvh", "leads out of")])
def test_a_clip_outside_the_folder_is_refused_naming_the_key(tmp_path, clip, problem):
    pack = tmp_path / "pack"
    with pytest.raises(ExternalReferenceError) as err:
        read_manifest(_write(pack, clip=clip))
    assert "clips[0].file" in str(err.value) and problem in str(err.value) and "manifest.toml" in str(err.value)


def test_a_link_out_of_the_folder_is_refused(tmp_path):
    pack = tmp_path / "pack"
    (pack / "clips").mkdir(parents=True)
    (tmp_path / "secret.bvh").write_text("HIERARCHY\n")
    (pack / "clips" / "a.bvh").symlink_to(tmp_path / "secret.bvh")
    with pytest.raises(ExternalReferenceError, match="leads out of"):
        read_manifest(_write(pack))


def test_a_device_is_refused(tmp_path):
    with pytest.raises(ExternalReferenceError, match="pack.skeleton"):
        with allow_external():
            read_manifest(_write(tmp_path, skeleton="/dev/zero"))


def test_the_user_may_allow_files_elsewhere(tmp_path):
    pack = tmp_path / "pack"
    with allow_external():
        manifest = read_manifest(_write(pack, clip="../shared/a.bvh"))
    assert manifest.clips[0].file == (tmp_path / "shared" / "a.bvh").resolve()
