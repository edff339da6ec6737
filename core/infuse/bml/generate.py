"""BML generators: plugins that add behaviours to a block before it is scheduled.

A generator (hook ``infuse_bml_generators``, :class:`~infuse.plugin_types.BMLGenerator`) gets a parsed
:class:`~infuse.bml.Block` and a :class:`GeneratorContext` and returns a :class:`Generation`: the block
with what it added, blocks for other characters (a listener's backchannel), and the added BML as text
(a ``<bml>`` document, or an ``<act>`` of several), which the scheduler reports as ``generatedBml`` feedback. A block turns generator
NAME on or off with the attribute ``infuse:NAME="true"`` / ``"false"`` (namespace ``urn:infuse:bml``);
a scheduler's ``generators`` are on for every block that does not say. The generators run in the order
of that list, each on the block the previous one returned.
"""
from __future__ import annotations

import zlib
from dataclasses import dataclass, field, replace
from typing import Callable

from .. import registry
from .model import CUSTOM_ATTRIBUTE_NOT_SUPPORTED, PARSING_FAILURE, Block, Issue

#: Prefix of the block attributes generators read.
PREFIX = "infuse:"
_TRUE, _FALSE = frozenset({"true", "yes", "on", "1"}), frozenset({"false", "no", "off", "0"})


class GenerationError(ValueError):
    """A generator cannot add to this block (a setting it cannot use...): a warning, the block plays unchanged."""


@dataclass(frozen=True)
class GeneratorContext:
    """What a generator may know about the scene.

    ``character``: who performs the block; ``characters``, ``objects``: every character and object of the
    scene by name (empty for a scheduler without a scene); ``locate(name)`` -> (x, y, z) metres or None;
    ``seed``: this block's seed (the scheduler's seed mixed with the block id and character, so a block's
    draws do not depend on the blocks before it); ``settings``: the block's ``infuse:`` attributes the
    generator declared, prefix dropped (name -> text); ``said``: the text of every speech scheduled before
    this block, by any character, oldest first (what the conversation has already said).
    """

    character: str | None
    dialect: str = "bml1.0"
    characters: tuple[str, ...] = ()
    objects: tuple[str, ...] = ()
    locate: Callable[[str], tuple | None] = lambda name: None
    seed: int = 0
    settings: dict = field(default_factory=dict)
    said: tuple[str, ...] = ()


@dataclass(frozen=True)
class Generation:
    """A generator's answer: ``block`` (the input with what was added), ``blocks`` (new blocks, each naming
    its character, scheduled after it at the same time), ``bml`` (everything added, as the text of a ``<bml>``
    document or of an ``<act>`` of several, ``""`` when nothing was) and ``notes`` (warnings about the block)."""

    block: Block
    blocks: tuple[Block, ...] = ()
    bml: str = ""
    notes: tuple[str, ...] = ()


def installed_generators() -> dict:
    """Name -> :class:`~infuse.plugin_types.BMLGenerator` of every installed generator."""
    return dict(registry.table("bml-generator"))


def block_seed(seed: int, block: Block, character: str | None) -> int:
    """A 32-bit seed for ``block``, the same in every process (``hash`` is salted; crc32 is not)."""
    return zlib.crc32(f"{int(seed)}|{block.id}|{character or ''}".encode("utf-8"))


def choose(block: Block, defaults, table: dict) -> tuple[list, dict, list[Issue]]:
    """(generators to run in order, name -> its settings, issues) for ``block``: ``defaults`` (names) unless
    the block turns them off, then those the block turns on; unknown ``infuse:`` attributes are issues."""
    wanted = list(defaults)
    settings: dict[str, dict] = {name: {} for name in table}
    issues: list[Issue] = []
    for key, value in block.attributes.items():
        if not key.startswith(PREFIX):
            continue
        name = key[len(PREFIX):]
        if name in table:
            flag = value.strip().lower()
            if flag not in _TRUE | _FALSE:
                issues.append(Issue(block.id, PARSING_FAILURE, f"block attribute {key}={value!r} is neither true nor "
                                                               f"false; generator {name!r} stays as it was", block.line))
            elif flag in _TRUE and name not in wanted:
                wanted.append(name)
            elif flag in _FALSE and name in wanted:
                wanted.remove(name)
            continue
        owners = [g for g, generator in table.items() if name in generator.attributes]
        for owner in owners:
            settings[owner][name] = value
        if not owners:
            known = ", ".join(sorted(PREFIX + n for n in table)) or "none installed"
            issues.append(Issue(block.id, CUSTOM_ATTRIBUTE_NOT_SUPPORTED,
                                f"block attribute {key!r} names no installed BML generator ({known}) and is ignored",
                                block.line))
    return [table[name] for name in wanted if name in table], settings, issues


def with_issues(block: Block, issues) -> Block:
    """``block`` with more issues (reported as warningFeedback when it is scheduled)."""
    return replace(block, issues=tuple(block.issues) + tuple(issues)) if issues else block
