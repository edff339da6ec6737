"""The realization seam in a scene: a plugin's ``realize`` gets the scene's Stage (names, places, its
stagehand), and the scene asks the stagehand before each block, ends blocks where it asks and runs until
it is done."""
from __future__ import annotations

import inspect
import types

import pytest

import infuse
from infuse import registry
from infuse.plugin_types import ControllerFactory
from infuse.scene import Scene
from infuse.scene.stage import SceneStage
from infuse.stage import Stage

from runtime_characters import corpus_character


def test_the_scene_stage_offers_everything_the_protocol_names():
    wanted = {name for name in vars(Stage) if not name.startswith("_")} | set(Stage.__annotations__)
    missing = sorted(name for name in wanted if not hasattr(SceneStage, name) and name not in ("fps", "runtime"))
    assert not missing
    for name, member in vars(Stage).items():
        if inspect.isfunction(member) and not name.startswith("_"):
            assert list(inspect.signature(getattr(SceneStage, name)).parameters) == \
                list(inspect.signature(member).parameters), name


class Marks:
    """A stagehand that wants a block to end at frame 10 and the scene to run until 2 s."""

    def __init__(self, stage):
        self.stage = stage
        self.blocks_from: list[int] = []

    def before_block(self) -> None:
        self.blocks_from.append(self.stage.runtime.frame)

    def frames_ahead(self, most: int) -> int:
        frame = self.stage.runtime.frame
        return 10 - frame if frame < 10 else most

    def end_s(self) -> float:
        return 2.0


@pytest.fixture
def seen(monkeypatch, tmp_path):
    """A program-registered controller that realizes BML ``head`` behaviours by looking around the stage."""
    monkeypatch.setenv("INFUSE_CONFIG", str(tmp_path / "absent.toml"))
    monkeypatch.delenv("INFUSE_DEFAULT_CONTROLLER_HEAD", raising=False)
    seen = {}

    def realize(activation, stage):
        seen["marks"] = stage.stagehand("marks", Marks)
        seen["same hand"] = stage.stagehand("marks", Marks) is seen["marks"]
        seen["what"] = {n: stage.what(stage.resolve(n)) for n in ("BOB", "cup", "spot", "nobody")}
        seen["located"] = stage.locate("bob")
        stage.set_destination("bob", 1.0, 2.0)
        seen["destination"] = stage.locate("bob")
        return None

    module = types.ModuleType("stage_probe")
    module.infuse_controllers = infuse.hookimpl(lambda: [ControllerFactory(
        "stage-probe", lambda: None, realize=realize, realizes=("head",))])
    registry.plugins().register(module)
    yield seen
    registry.plugins().unregister(module)


def test_a_realizing_plugin_sees_the_stage_and_its_stagehand_cuts_blocks(seen):
    scene = Scene(fps=30, quiet=True, idle=False)
    scene.add_character(corpus_character("xbot"), "bob")
    scene.add_object("cup", (0.3, 1.0, 0.4))
    scene.add_target("spot", (0.0, 1.5, 2.0))
    scene.nod("bob")
    assert seen["same hand"] and scene.stagehands["marks"] is seen["marks"]
    assert seen["what"] == {"BOB": "character", "cup": "object", "spot": "target", "nobody": None}
    assert seen["located"] == (0.0, 0.0, 0.0) and seen["destination"] == (1.0, 0.0, 2.0)
    assert scene.end_time == pytest.approx(2.0)  # what the stagehand follows ends at 2 s
    scene.run()
    assert scene.runtime.frame == 61  # up to the first frame at or after 2 s
    assert seen["marks"].blocks_from[:2] == [0, 10]  # the first block ends where the stagehand asked
    assert seen["marks"].blocks_from == sorted(set(seen["marks"].blocks_from))
