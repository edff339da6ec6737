"""Which installed controller realizes a BML behaviour kind (``registry.realizer``): the one named after the
kind, a replacement that lists the kind in ``realizes``, an explicit choice (environment variable or
configuration file), and the warning when several replacements compete; the choice kept until one of its
inputs changes, and the configuration looked at once for a whole BML block (held_config)."""
from __future__ import annotations

import os
import threading
import types

import pytest

import infuse
from infuse import registry
from infuse.errors import UsageError
from infuse.plugin_types import ControllerFactory


def _controllers_module(name: str, *factories: ControllerFactory) -> types.ModuleType:
    module = types.ModuleType(name)

    @infuse.hookimpl
    def infuse_controllers():
        return list(factories)

    module.infuse_controllers = infuse_controllers
    return module


@pytest.fixture
def settings(monkeypatch, tmp_path):
    """No user configuration and no realizer variable; returns the configuration file's path."""
    config = tmp_path / "config.toml"
    monkeypatch.setenv("INFUSE_CONFIG", str(config))
    monkeypatch.delenv("INFUSE_DEFAULT_CONTROLLER_GAZE", raising=False)
    monkeypatch.delenv("INFUSE_DEFAULT_CONTROLLER_HEAD", raising=False)
    return config


@pytest.fixture
def registered():
    """Register program modules for one test: ``registered(module)``."""
    modules = []

    def register(module):
        registry.plugins().register(module)
        modules.append(module)

    yield register
    for module in modules:
        registry.plugins().unregister(module)


def _gaze(**options):
    return registry.table("controller")["gaze"].factory(**options)


def test_the_controller_named_after_a_kind_realizes_it(settings):
    assert registry.realizer("gaze").name == "gaze"
    assert registry.realizer("head").name == "head"
    assert registry.realizer("no-such-kind") is None


def test_a_replacement_wins_over_the_controller_named_after_the_kind(settings, registered, capsys):
    registered(_controllers_module("soft_gaze", ControllerFactory("soft-gaze", _gaze, realizes=("gaze",))))
    assert registry.realizer("gaze").name == "soft-gaze"
    assert registry.realizer("head").name == "head"  # other kinds keep theirs
    assert "controller" not in capsys.readouterr().err  # one replacement: nothing to warn about


def test_several_replacements_warn_and_the_first_by_name_wins(settings, registered, capsys):
    registered(_controllers_module("zeta_gaze", ControllerFactory("zeta-gaze", _gaze, realizes=("gaze",))))
    registered(_controllers_module("alpha_gaze", ControllerFactory("alpha-gaze", _gaze, realizes=("gaze", "head"))))
    assert registry.realizer("gaze").name == "alpha-gaze"
    err = capsys.readouterr().err
    assert "2 controllers replace BML 'gaze' behaviours" in err
    assert "alpha-gaze" in err and "zeta-gaze" in err and "INFUSE_DEFAULT_CONTROLLER_GAZE" in err
    assert registry.realizer("head").name == "alpha-gaze"  # one factory may realize several kinds


def test_an_explicit_choice_wins_environment_first(settings, registered, monkeypatch):
    registered(_controllers_module("soft_gaze", ControllerFactory("soft-gaze", _gaze, realizes=("gaze",))))
    settings.write_text('[defaults.controller]\ngaze = "gaze"\n')
    assert registry.realizer("gaze").name == "gaze"  # the configuration file brings the built-in back
    monkeypatch.setenv("INFUSE_DEFAULT_CONTROLLER_GAZE", "soft-gaze")
    assert registry.realizer("gaze").name == "soft-gaze"  # the variable wins over the file


def test_choosing_a_controller_that_does_not_realize_the_kind_is_an_error(settings, monkeypatch):
    monkeypatch.setenv("INFUSE_DEFAULT_CONTROLLER_GAZE", "blink")
    with pytest.raises(UsageError, match="INFUSE_DEFAULT_CONTROLLER_GAZE names controller 'blink'.*those that do: gaze"):
        registry.realizer("gaze")


def test_a_realizer_table_in_the_configuration_must_hold_strings(settings):
    settings.write_text("[defaults.controller]\ngaze = 3\n")
    with pytest.raises(infuse.InputError, match=r"\[defaults.controller\] gaze.*must be a string"):
        registry.realizer("gaze")


def test_the_choice_is_kept_until_one_of_its_inputs_changes(settings, registered, monkeypatch):
    """The realizer is looked up for every behaviour realized: the configuration file is read once while it
    stays as it is, and the choice is made again when a controller registers, the file appears or is
    rewritten (even keeping its modification time) or the variable is set."""
    from infuse import config

    reads = []
    read = config.read_config
    monkeypatch.setattr(config, "read_config", lambda path, kinds: reads.append(path) or read(path, kinds))
    assert registry.realizer("gaze").name == "gaze"  # no file
    registered(_controllers_module("soft_gaze", ControllerFactory("soft-gaze", _gaze, realizes=("gaze",))))
    assert registry.realizer("gaze").name == "soft-gaze"
    settings.write_text('[defaults.controller]\ngaze = "gaze"\n')
    for _ in range(3):
        assert registry.realizer("gaze").name == "gaze"
    assert len(reads) == 1
    written = settings.stat()
    settings.write_text('[defaults.controller]\ngaze = "soft-gaze"\n')
    os.utime(settings, ns=(written.st_atime_ns, written.st_mtime_ns))
    assert registry.realizer("gaze").name == "soft-gaze"
    assert len(reads) == 2
    monkeypatch.setenv("INFUSE_DEFAULT_CONTROLLER_GAZE", "gaze")
    assert registry.realizer("gaze").name == "gaze"
    monkeypatch.setenv("INFUSE_CONFIG", str(settings.with_name("elsewhere.toml")))
    monkeypatch.delenv("INFUSE_DEFAULT_CONTROLLER_GAZE")
    assert registry.realizer("gaze").name == "soft-gaze"  # no file there: the replacement again


def test_a_held_configuration_is_looked_at_once_on_its_thread(settings, registered):
    """Within held_config (one scheduled BML block), lookups on its thread see the configuration of the first
    look, nested or not; another thread looks for itself, and after it the file is looked at again."""
    from infuse import config

    registered(_controllers_module("soft_gaze", ControllerFactory("soft-gaze", _gaze, realizes=("gaze",))))
    settings.write_text('[defaults.controller]\ngaze = "gaze"\n')
    elsewhere = {}
    with config.held_config():
        assert registry.realizer("gaze").name == "gaze"
        settings.write_text('[defaults.controller]\ngaze = "soft-gaze"\n')
        with config.held_config():
            assert registry.realizer("gaze").name == "gaze"
        other = threading.Thread(target=lambda: elsewhere.update(name=registry.realizer("gaze").name))
        other.start()
        other.join()
        assert registry.realizer("gaze").name == "gaze"  # the nested one did not let go
    assert elsewhere["name"] == "soft-gaze"
    assert registry.realizer("gaze").name == "soft-gaze"
