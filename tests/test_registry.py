"""The plugin registry: lazy kinds, defaults and their precedence, name clashes, validated hooks; and the
command line that lists commands without importing their plugins.

Plugins under test are distributions made in a temporary folder (a ``.dist-info`` with entry points
beside their modules) and put on ``PYTHONPATH`` of a child process, so the shared environment is
untouched; each child gets its own cache and configuration folders.
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pluggy
import pytest

import infuse
from infuse import registry
from infuse.errors import InputError, UsageError


def make_distribution(site: Path, name: str, entry_points: str, modules: dict[str, str]) -> None:
    """A distribution ``name`` 0.1.0 in ``site``: its entry points (INI text) and its modules (name -> source)."""
    info = site / f"{name.replace('-', '_')}-0.1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text(textwrap.dedent(entry_points))
    for module, source in modules.items():
        (site / f"{module}.py").write_text(textwrap.dedent(source))


def child(site: Path | None, code: str, home: Path, **env_vars: str) -> subprocess.CompletedProcess:
    """Run ``code`` in a child Python with ``site`` on its path and its own cache and config folders."""
    env = dict(os.environ, XDG_CACHE_HOME=str(home / "cache"), XDG_CONFIG_HOME=str(home / "config"), **env_vars)
    for name in ("INFUSE_DEBUG", "INFUSE_CONFIG", *(k.environment_variable for k in registry.KINDS.values())):
        if name not in env_vars:
            env.pop(name, None)
    if site is not None:
        env["PYTHONPATH"] = str(site)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)


def infuse_cli(site: Path | None, home: Path, *args: str, **env_vars: str) -> subprocess.CompletedProcess:
    return child(site, f"from infuse.cli import main; raise SystemExit(main({list(args)!r}))", home, **env_vars)


# -- defaults --------------------------------------------------------------------------------------


@pytest.fixture
def no_user_settings(monkeypatch, tmp_path):
    monkeypatch.setenv("INFUSE_CONFIG", str(tmp_path / "absent.toml"))
    for kind in registry.KINDS.values():
        monkeypatch.delenv(kind.environment_variable, raising=False)
    return tmp_path


def test_built_in_defaults(no_user_settings):
    assert registry.default_name("mapper") == ("heuristic", "built-in default")
    assert registry.get("mapper").name == "heuristic"
    assert registry.get("retargeter").name == "default"
    assert registry.default_name("reader") == (None, "built-in default")
    with pytest.raises(UsageError, match="name a reader: there is no default reader; installed: .*bvh"):
        registry.get("reader")


def test_environment_over_config_file_over_built_in(no_user_settings, monkeypatch):
    config = no_user_settings / "config.toml"
    config.write_text('[defaults]\nmapper = "names"\nretargeter = "paper"\n')
    monkeypatch.setenv("INFUSE_CONFIG", str(config))
    assert registry.get("mapper").name == "names"
    assert registry.get("retargeter").name == "paper"
    monkeypatch.setenv("INFUSE_DEFAULT_MAPPER", "heuristic")
    assert registry.default_name("mapper") == ("heuristic", "INFUSE_DEFAULT_MAPPER")
    assert registry.get("mapper").name == "heuristic"
    assert registry.get("mapper", "names").name == "names"  # a name given in the call wins over every default


def test_a_default_that_is_not_installed_says_where_it_was_set(no_user_settings, monkeypatch):
    monkeypatch.setenv("INFUSE_DEFAULT_MAPPER", "nope")
    with pytest.raises(UsageError, match=r"no mapper named 'nope' \(the default, from INFUSE_DEFAULT_MAPPER\); "
                                         r"installed: .*heuristic"):
        registry.get("mapper")
    with pytest.raises(UsageError, match="no plugin kind 'mappers'; the kinds are reader, writer, mapper"):
        registry.get("mappers")


@pytest.mark.parametrize("text, place", [
    ('[defaults]\nmapper = 3\n', r":\[defaults\] mapper: must be a string, not int"),
    ('[defaults]\nmappers = "names"\n', r":\[defaults\] mappers: unknown plugin kind; the kinds are .*mapper"),
    ('[default]\nmapper = "names"\n', r":\[default\]: unknown section"),
    ('[prefer]\nmapper = "x"\n', r":\[prefer\] mapper: must be a table of names, not str"),
    ('[defaults\nmapper = "names"\n', r": not valid TOML: .*line 1"),
])
def test_malformed_config_names_the_file_and_the_place(no_user_settings, monkeypatch, text, place):
    config = no_user_settings / "bad.toml"
    config.write_text(text)
    monkeypatch.setenv("INFUSE_CONFIG", str(config))
    with pytest.raises(InputError, match="^" + re.escape(str(config)) + place):
        registry.get("mapper")


def test_malformed_config_is_one_line_and_exit_code_2(tmp_path):
    config = tmp_path / "config.toml"
    config.write_text('[defaults]\nmapper = ["names"]\n')
    bvh = tmp_path / "one.bvh"
    bvh.write_text(ONE_JOINT_BVH)
    proc = infuse_cli(None, tmp_path, "map", str(bvh), INFUSE_CONFIG=str(config))
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"infuse: error: {config}:[defaults] mapper: must be a string, not list"


# -- registering, validating, clashing ---------------------------------------------------------------


def _module(name: str, source: str):
    import types

    module = types.ModuleType(name)
    exec(textwrap.dedent(source), module.__dict__)
    return module


def test_program_plugins_win_their_names_and_misspelled_hooks_are_refused(no_user_settings):
    plugins = registry.plugins()
    fake = _module("program_mapper", """
        import infuse
        from infuse.plugin_types import Mapper

        def map_nothing(skeleton, **options):
            raise AssertionError("not called")

        @infuse.hookimpl
        def infuse_mappers():
            return [Mapper("names", map_nothing, "the program's own 'names'")]
        """)
    plugins.register(fake)
    try:
        assert registry.get("mapper", "names").description == "the program's own 'names'"
    finally:
        plugins.unregister(fake)
    assert registry.get("mapper", "names").description != "the program's own 'names'"
    misspelled = _module("misspelled_mapper", """
        import infuse

        @infuse.hookimpl
        def infuse_mapper():
            return []
        """)
    with pytest.raises(pluggy.PluginValidationError, match="unknown hook 'infuse_mapper'"):
        plugins.register(misspelled)
    assert not plugins.manager.is_registered(misspelled)


@pytest.fixture(scope="module")
def odd_site(tmp_path_factory) -> Path:
    """Installed plugins that clash with the built-in names mapper, misspell or forget the marker, or return junk."""
    site = tmp_path_factory.mktemp("site")
    make_distribution(site, "infuse-test-clash", """\
        [infuse.mappers]
        other-names = infuse_test_clash
        misspelled = infuse_test_misspelled
        unmarked = infuse_test_unmarked
        junk = infuse_test_junk
        arguments = infuse_test_arguments
        """, {
        "infuse_test_clash": """\
            import infuse
            from infuse.plugin_types import Mapper

            def map_nothing(skeleton, **options):
                raise AssertionError("not called")

            @infuse.hookimpl
            def infuse_mappers():
                return [Mapper("names", map_nothing, "a second names mapper")]
            """,
        "infuse_test_misspelled": """\
            import infuse

            @infuse.hookimpl
            def infuse_mapper():
                return []
            """,
        "infuse_test_unmarked": """\
            def infuse_mappers():
                return []
            """,
        "infuse_test_junk": """\
            import infuse

            @infuse.hookimpl
            def infuse_mappers():
                return ["not a descriptor"]
            """,
        "infuse_test_arguments": """\
            import infuse

            @infuse.hookimpl
            def infuse_mappers(skeleton):
                return []
            """,
    })
    return site


LIST_MAPPERS = "from infuse import registry; print({n: m.description for n, m in registry.table('mapper').items()})"


def test_a_name_clash_is_warned_once_and_resolved_the_same_way_everywhere(odd_site, tmp_path):
    proc = child(odd_site, LIST_MAPPERS + "; registry.table('mapper')", tmp_path)
    assert proc.returncode == 0, proc.stderr
    table = eval(proc.stdout)
    builtin = registry.plugins().records
    names_dist = next(r.distribution for r in builtin if (r.name, r.kind) == ("names", "mapper"))
    winner = min(names_dist, "infuse-test-clash")  # the first by distribution name
    assert (table["names"] == "a second names mapper") == (winner == "infuse-test-clash")
    clash = [line for line in proc.stderr.splitlines() if "plugins are named 'names'" in line]
    assert len(clash) == 1, proc.stderr
    assert f"infuse: warning: 2 mapper plugins are named 'names': {min(names_dist, 'infuse-test-clash')}" in clash[0]
    assert f"using {winner}'s (choose with [prefer.mapper] names = \"DISTRIBUTION\" in " in clash[0]


def test_the_config_file_chooses_between_clashing_plugins_without_a_warning(odd_site, tmp_path):
    loser = "infuse-test-clash"
    config = tmp_path / "config.toml"
    config.write_text(f'[prefer.mapper]\nnames = "{loser}"\n')
    proc = child(odd_site, LIST_MAPPERS, tmp_path, INFUSE_CONFIG=str(config))
    assert proc.returncode == 0, proc.stderr
    assert eval(proc.stdout)["names"] == "a second names mapper"
    assert "plugins are named 'names'" not in proc.stderr


def test_invalid_plugins_are_reported_and_skipped(odd_site, tmp_path):
    proc = child(odd_site, LIST_MAPPERS, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert {"heuristic", "names"} <= set(eval(proc.stdout))
    warnings = proc.stderr
    assert ("plugin 'misspelled' (infuse-test-clash, group infuse.mappers) is invalid and is skipped: "
            "unknown hook 'infuse_mapper'") in warnings
    assert ("plugin 'infuse-test-clash:infuse_test_unmarked' defines infuse_mappers() without @infuse.hookimpl: "
            "infuse does not call it") in warnings
    assert ("plugin 'infuse-test-clash:infuse_test_junk' returned str from infuse_mappers, not a named Mapper; "
            "it is skipped") in warnings
    assert "plugin 'arguments' (infuse-test-clash, group infuse.mappers) is invalid and is skipped: " in warnings
    assert "'skeleton'" in warnings  # the argument the hook's specification does not have
    listing = infuse_cli(odd_site, tmp_path, "plugins", "--json")
    records = {r["name"]: r for r in json.loads(listing.stdout)}
    assert records["misspelled"]["error"].startswith("invalid plugin: unknown hook 'infuse_mapper'")
    assert records["arguments"]["error"].startswith("invalid plugin: ")
    assert records["junk"]["error"] is None and records["heuristic"]["error"] is None


def test_a_kind_is_loaded_when_first_asked_for(tmp_path):
    code = ("import sys; from infuse import registry; registry.table('reader'); "
            "print(sorted(m for m in sys.modules if m.startswith('infuse_') and m.count('.') == 0))")
    proc = child(None, code, tmp_path)
    assert proc.returncode == 0, proc.stderr
    loaded = set(eval(proc.stdout))
    readers = {r.module.split(".")[0] for r in registry.plugins().records if r.kind == "reader"}
    only_others = {r.module.split(".")[0] for r in registry.plugins().records if r.kind != "reader"} - readers
    assert readers <= loaded and not (only_others & loaded), only_others & loaded


ONE_JOINT_BVH = ("HIERARCHY\nROOT hips\n{\n OFFSET 0 1 0\n CHANNELS 3 Zrotation Xrotation Yrotation\n"
                 " End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\nFrames: 1\nFrame Time: 0.04\n0 0 0\n")


def test_a_file_is_read_importing_only_the_readers_of_its_extension(tmp_path):
    bvh = tmp_path / "one.bvh"
    bvh.write_text(ONE_JOINT_BVH)
    readers = {r.module.split(".")[0] for r in registry.plugins().records if r.kind == "reader"}
    bvh_plugin = {r.module.split(".")[0] for r in registry.plugins().records if (r.kind, r.name) == ("reader", "bvh")}
    code = (f"import sys, infuse; asset = infuse.load({str(bvh)!r}); "
            f"print(asset.format, sorted(set({sorted(readers)!r}) & set(sys.modules)))")
    first = child(None, code, tmp_path)  # learns what every reader offers
    assert first.returncode == 0, first.stderr
    second = child(None, code, tmp_path)
    assert second.returncode == 0, second.stderr
    assert second.stdout.split(None, 1) == ["bvh", f"{sorted(bvh_plugin)!r}\n"]
    bvh.rename(bvh.with_suffix(".nope"))
    unknown = child(None, f"import infuse; infuse.load({str(bvh.with_suffix('.nope'))!r})", tmp_path)
    last = unknown.stderr.strip().splitlines()[-1]
    assert "UnsupportedFormatError" in last and "no installed reader handles '.nope'; known: " in last
    assert all(e in last for e in (".bvh", ".glb", ".dae", ".fbx"))


def test_importing_infuse_loads_neither_numpy_nor_scipy(tmp_path):
    code = ("import sys, infuse, infuse.quaternions as q; q.to_matrix(q.identity()); heavy = {'scipy', 'pluggy'}; "
            "print(sorted(heavy & set(sys.modules)), 'numpy' in sys.modules, infuse.Skeleton.__name__)")
    proc = child(None, code, tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["[]", "True", "Skeleton"]
    proc = child(None, "import sys, infuse; print(infuse.__version__, 'numpy' in sys.modules)", tmp_path)
    assert proc.stdout.split() == [infuse.__version__, "False"]
    with pytest.raises(AttributeError, match="module 'infuse' has no attribute 'nonexistent'"):
        infuse.nonexistent  # noqa: B018


# -- the command line --------------------------------------------------------------------------------


HELLO = """\
    from infuse import hookimpl
    from infuse.plugin_types import Command

    def _arguments(parser):
        parser.add_argument("who")

    def _run(args):
        print(f"hello {{args.who}}")
        return 0

    @hookimpl
    def infuse_commands():
        return [Command("hello", "{help}", _arguments, _run)]
    """


@pytest.fixture
def hello_site(tmp_path) -> Path:
    site = tmp_path / "site"
    make_distribution(site, "infuse-test-hello", "[infuse.commands]\ngreetings = infuse_test_hello\n",
                      {"infuse_test_hello": HELLO.format(help="say hello")})
    return site


PLUGIN_MODULES = ("import sys; print(sorted(m for m in sys.modules if m.split('.')[0] in {plugins!r} "
                  "or m in ('numpy', 'scipy')))")


def _plugin_packages() -> set[str]:
    return {r.module.split(".")[0] for r in registry.plugins().records} - {"infuse"} | {"infuse_test_hello"}


def test_help_lists_commands_without_importing_them(hello_site, tmp_path):
    first = infuse_cli(hello_site, tmp_path, "--help")  # learns the commands and caches them
    assert first.returncode == 0, first.stderr
    assert "hello" in first.stdout and "say hello" in first.stdout and "info" in first.stdout
    code = ("from infuse.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            + PLUGIN_MODULES.format(plugins=sorted(_plugin_packages())))
    second = child(hello_site, code, tmp_path)
    assert second.returncode == 0, second.stderr
    assert "say hello" in second.stdout
    assert second.stdout.strip().splitlines()[-1] == "[]"
    run = child(hello_site, "from infuse.cli import main; main(['hello', 'you'])\n"
                + PLUGIN_MODULES.format(plugins=sorted(_plugin_packages())), tmp_path)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.strip().splitlines()
    assert lines[0] == "hello you" and lines[1] == "['infuse_test_hello']"


def test_an_edited_command_plugin_is_learnt_again(hello_site, tmp_path):
    assert "say hello" in infuse_cli(hello_site, tmp_path, "--help").stdout
    module = hello_site / "infuse_test_hello.py"
    module.write_text(textwrap.dedent(HELLO.format(help="greet someone by name")))
    stat = module.stat()
    os.utime(module, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000_000))  # a later edit, even on coarse clocks
    again = infuse_cli(hello_site, tmp_path, "--help")
    assert "greet someone by name" in again.stdout and "say hello" not in again.stdout
    assert infuse_cli(hello_site, tmp_path, "hello", "me").stdout == "hello me\n"


def test_a_command_offered_twice_is_warned_and_the_config_chooses(hello_site, tmp_path):
    make_distribution(hello_site, "infuse-test-hello-again", "[infuse.commands]\nhello = infuse_test_hello_again\n",
                      {"infuse_test_hello_again": HELLO.format(help="say hello again").replace("hello {", "hi {")})
    proc = infuse_cli(hello_site, tmp_path, "hello", "you")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "hello you\n"
    assert ("2 command plugins are named 'hello': infuse-test-hello (infuse_test_hello) and "
            "infuse-test-hello-again (infuse_test_hello_again); using infuse-test-hello's") in proc.stderr
    config = tmp_path / "config.toml"
    config.write_text('[prefer.command]\nhello = "infuse-test-hello-again"\n')
    chosen = infuse_cli(hello_site, tmp_path, "hello", "you", INFUSE_CONFIG=str(config))
    assert chosen.stdout == "hi you\n" and "warning" not in chosen.stderr


def test_version_and_usage(tmp_path):
    proc = infuse_cli(None, tmp_path, "--version")
    assert proc.returncode == 0 and proc.stdout == f"infuse {infuse.__version__}\n"
    proc = infuse_cli(None, tmp_path)
    assert proc.returncode == 2 and "COMMAND" in proc.stdout and "info" in proc.stdout
    proc = infuse_cli(None, tmp_path, "nosuchcommand")
    assert proc.returncode == 2 and "invalid choice: 'nosuchcommand'" in proc.stderr


def test_the_command_index_matches_the_full_parser():
    from infuse.cli import build_parser
    from infuse.cli.index import command_index

    full = build_parser()
    (choices,) = [a.choices for a in full._actions if isinstance(getattr(a, "choices", None), dict)]
    index = command_index()
    assert set(index) == set(choices)
    assert all(index[name][0].description == choices[name].description for name in index)



def test_the_index_knows_the_extensions_the_readers_and_writers_claim():
    for kind in ("reader", "writer"):
        claimed = {e for d in registry.table(kind).values() for e in d.extensions}
        assert registry.extensions(kind) == claimed and ".bvh" in claimed


def test_infuse_plugins_says_which_defaults_are_in_effect(no_user_settings, monkeypatch, capsys):
    from infuse.cli import main

    monkeypatch.setenv("INFUSE_DEFAULT_MAPPER", "names")
    assert main(["plugins"]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last == ("defaults: mapper names (INFUSE_DEFAULT_MAPPER), retargeter default (built-in default), "
                    "tts espeak (built-in default)")
