"""Safe parsing of BML 1.0, the SmartBody dialect and the pre-1.0 draft into :mod:`infuse.bml.model`.

The XML parser never resolves entities, never loads a DTD, never touches the network and refuses
documents with a DOCTYPE or larger than ``max_bytes``. SmartBody documents use the ``sbm:`` prefix
without declaring it: undeclared prefixes are bound before parsing (``sbm`` to SmartBody's own URI,
``infuse`` to infuse's, others to a placeholder so their attributes can be reported as unknown rather
than failing the file).
"""
from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

from lxml import etree

from .. import limits
from ..errors import InputError
from . import names
from .model import (
    COMPOSITIONS, CUSTOM_ATTRIBUTE_NOT_SUPPORTED, DIALECT_BML1, DIALECT_DRAFT, DIALECT_SMARTBODY, PARSING_FAILURE,
    Behaviour, Block, BmlDocument, Constraint, Issue, Node,
)
from .sync import SYNC_ATTRIBUTES, SyncRefError, canonical_sync, parse_sync_ref

#: Largest document accepted, in bytes.
DEFAULT_MAX_BYTES = 8 * 1024 * 1024

#: Inline speech marks: element -> attribute holding the mark's id.
MARK_ELEMENTS = {"sync": "id", "tm": "id", "mark": "name"}
_UNDEFINED_PREFIX = re.compile(r"Namespace prefix (\S+) (?:for \S+ )?on \S+ is not defined")
_PROLOG_ITEM = re.compile(rb"\s*(?:<\?.*?\?>|<!--.*?-->)", re.S)
_ROOT_NAME = re.compile(rb"\s*<([^\s/>!?]+)")
_ENCODING_DECL = re.compile(r"^(\s*<\?xml[^>]*?)\s+encoding\s*=\s*(['\"])[^'\"]*\2")
_NS_ERROR = 201  # libxml2 XML_NS_ERR_UNDEFINED_NAMESPACE
#: Prefixes a document may use without declaring them, and their namespaces.
_IMPLIED = {"sbm": names.SBM_NS, "infuse": names.INFUSE_NS}
_BLOCK_ATTRIBUTES = {"id", "characterId", "character", "composition", "bmla:appendAfter", "bmla:chunkAfter",
                     "bmla:interrupt", "sbm:character"}


def parse_bml_file(path: str | Path, max_bytes: int = DEFAULT_MAX_BYTES) -> BmlDocument:
    """Parse a BML file. Malformed or unsafe input raises :class:`InputError` naming the file and line."""
    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise InputError(path, None, f"cannot be read: {exc.strerror or exc}") from None
    if size > max_bytes:
        raise InputError(path, None, f"is {size} bytes; BML documents larger than {max_bytes} bytes are refused")
    return parse_bml(path.read_bytes(), file=str(path), max_bytes=max_bytes)


def parse_bml(source: str | bytes, file: str | None = None, max_bytes: int = DEFAULT_MAX_BYTES) -> BmlDocument:
    """Parse BML from a string or bytes; ``file`` names it in errors (default ``"<bml>"``)."""
    label = file or "<bml>"
    if isinstance(source, str):
        # The text is already decoded: an encoding declaration would now be wrong.
        data = _ENCODING_DECL.sub(r"\1", source, count=1).encode("utf-8")
    else:
        data = bytes(source)
    if len(data) > max_bytes:
        raise InputError(label, None, f"is {len(data)} bytes; BML documents larger than {max_bytes} bytes are refused")
    tree, declared = _parse_xml(data, label)
    if tree.docinfo.doctype or tree.docinfo.internalDTD is not None:
        raise InputError(label, "line 1", "DOCTYPE declarations are refused in BML (no DTDs, entities or external references)")
    root = tree.getroot()
    elements = sum(1 for _ in root.iter(tag=etree.Element))
    limits.check(label, None, "elements (behaviours, constraints, blocks, marks)", elements, "MAX_BML_ELEMENTS")
    comments = tuple(c.text or "" for c in reversed(list(root.itersiblings(preceding=True)))
                     if isinstance(c, etree._Comment))
    return BmlDocument(_blocks(root, label, declared), file=file, comments=comments)


def _new_parser() -> etree.XMLParser:
    return etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False,
                           dtd_validation=False, remove_pis=True, recover=False)


def _parse_xml(data: bytes, label: str):
    """The lxml tree, and the prefixes infuse had to declare itself."""
    parser = _new_parser()
    try:
        return etree.ElementTree(etree.fromstring(data, parser)), ()
    except etree.XMLSyntaxError as exc:
        errors = list(parser.error_log)
        prefixes = sorted({m.group(1) for e in errors if e.type == _NS_ERROR for m in [_UNDEFINED_PREFIX.search(e.message)] if m})
        if not prefixes or any(e.type != _NS_ERROR for e in errors if e.level_name in ("ERROR", "FATAL")):
            raise _syntax_error(exc, errors, label) from None
    patched = _declare_prefixes(data, prefixes)
    if patched is None:
        raise InputError(label, None, f"undeclared namespace prefix {', '.join(prefixes)} and no root element found")
    parser = _new_parser()
    try:
        return etree.ElementTree(etree.fromstring(patched, parser)), tuple(prefixes)
    except etree.XMLSyntaxError as exc:
        raise _syntax_error(exc, list(parser.error_log), label) from None


def _syntax_error(exc: etree.XMLSyntaxError, log: list, label: str) -> InputError:
    errors = [e for e in log if e.level_name in ("ERROR", "FATAL")]
    first = errors[0] if errors else None
    line = first.line if first is not None else exc.lineno
    message = first.message if first is not None else str(exc.msg)
    return InputError(label, f"line {line}", f"malformed XML: {message.strip()}")


def _declare_prefixes(data: bytes, prefixes) -> bytes | None:
    """``data`` with ``xmlns:p`` declarations added to the root start tag (same line, so line numbers hold)."""
    pos = 0
    while True:
        m = _PROLOG_ITEM.match(data, pos)
        if not m:
            break
        pos = m.end()
    m = _ROOT_NAME.match(data, pos)
    if not m:
        return None
    decls = "".join(f' xmlns:{p}="{_IMPLIED.get(p, names.UNDECLARED_NS + p)}"' for p in prefixes)
    return data[:m.end()] + decls.encode("ascii") + data[m.end():]


def _elements(parent):
    return [c for c in parent if isinstance(c.tag, str)]


def _blocks(root, label: str, declared: tuple) -> tuple[Block, ...]:
    root_name = names.element_name(root.tag)
    if root_name == "act":
        block_elements = [c for c in _elements(root) if names.element_name(c.tag) == "bml"]
        if not block_elements:
            raise InputError(label, f"line {root.sourceline}", "<act> holds no <bml> block")
    elif root_name == "bml":
        block_elements = [root]
    else:
        raise InputError(label, f"line {root.sourceline}", f"root element is <{root_name}>, expected <bml> or <act>")
    blocks = []
    used_ids: set[str] = set()
    for index, element in enumerate(block_elements):
        block = _block(element, root_name == "act", declared, index)
        if block.id in used_ids:
            raise InputError(label, f"line {element.sourceline}", f"two blocks have the id {block.id!r}")
        used_ids.add(block.id)
        blocks.append(block)
    return tuple(blocks)


def _dialect(element, in_act: bool) -> str:
    uri, _ = names.split_clark(element.tag)
    if uri == names.BML_DRAFT_NS:
        return DIALECT_DRAFT
    if in_act or uri == "":
        return DIALECT_SMARTBODY
    return DIALECT_BML1


def _id_list(value: str | None) -> tuple[str, ...]:
    return tuple(p.strip() for p in (value or "").split(",") if p.strip())


def _block(element, in_act: bool, declared: tuple, index: int) -> Block:
    attrs = {names.attribute_name(k): v for k, v in element.attrib.items()}
    issues: list[Issue] = []
    block_id = attrs.get("id") or f"bml{index + 1}"
    line = element.sourceline
    if "id" not in attrs and not in_act and names.split_clark(element.tag)[0] == names.BML_NS:
        issues.append(Issue(block_id, PARSING_FAILURE, "<bml> has no id; it was named " + repr(block_id), line))
    for prefix in declared:
        if prefix not in _IMPLIED:
            issues.append(Issue(block_id, PARSING_FAILURE, f"namespace prefix {prefix!r} is used but not declared", line))
    composition_text = (attrs.get("composition") or "MERGE").strip().upper()
    composition = {"BLEND": "MERGE"}.get(composition_text, composition_text)
    if composition not in COMPOSITIONS:
        issues.append(Issue(block_id, PARSING_FAILURE, f"unknown composition {composition_text!r}; MERGE is used", line))
        composition = "MERGE"
    for key in attrs:
        if key not in _BLOCK_ATTRIBUTES and not key.startswith("infuse:"):  # the scheduler's generators read those
            issues.append(Issue(block_id, CUSTOM_ATTRIBUTE_NOT_SUPPORTED, f"block attribute {key!r} is not supported and is ignored", line))
    behaviours: list[Behaviour] = []
    constraints: list[Constraint] = []
    _collect(element, block_id, False, behaviours, constraints, issues)
    behaviours = _unique_ids(behaviours, block_id, issues)
    return Block(
        id=block_id,
        character_id=attrs.get("characterId") or attrs.get("character") or attrs.get("sbm:character"),
        composition=composition,
        behaviours=tuple(behaviours),
        constraints=tuple(constraints),
        dialect=_dialect(element, in_act),
        append_after=_id_list(attrs.get("bmla:appendAfter")) + _id_list(attrs.get("bmla:chunkAfter")),
        interrupts=_id_list(attrs.get("bmla:interrupt")),
        attributes=attrs,
        issues=tuple(issues),
        line=line,
    )


def _collect(parent, block_id, required, behaviours, constraints, issues) -> None:
    for child in _elements(parent):
        name = names.element_name(child.tag)
        if name == "required":
            _collect(child, block_id, True, behaviours, constraints, issues)
        elif name == "constraint":
            constraints.extend(_constraints(child, block_id, required, issues))
        else:
            behaviours.append(_behaviour(child, name, required))


def _constraints(element, block_id, required, issues) -> list[Constraint]:
    out = []
    constraint_id = element.get("id")
    for kind_element in _elements(element):
        kind = names.element_name(kind_element.tag)
        line = kind_element.sourceline
        if kind not in ("synchronize", "before", "after"):
            issues.append(Issue(block_id, PARSING_FAILURE, f"unknown constraint <{kind}> is ignored", line))
            continue
        try:
            ref_text = kind_element.get("ref")
            ref = parse_sync_ref(ref_text) if ref_text is not None else None
            syncs = tuple(parse_sync_ref(s.get("ref", "")) for s in _elements(kind_element)
                          if names.element_name(s.tag) == "sync")
        except SyncRefError as exc:
            out.append(Constraint(kind, (), None, constraint_id, required, line, error=str(exc)))
            continue
        if kind in ("before", "after") and ref is None:
            out.append(Constraint(kind, syncs, None, constraint_id, required, line, error=f"<{kind}> needs a ref attribute"))
            continue
        out.append(Constraint(kind, syncs, ref, constraint_id, required, line))
    return out


def _behaviour(element, name: str, required: bool) -> Behaviour:
    sync_refs, sync_errors, attributes = {}, {}, {}
    for key, value in element.attrib.items():
        attr = names.attribute_name(key)
        if attr == "id":
            continue
        if attr in SYNC_ATTRIBUTES:
            sync = canonical_sync(attr)
            try:
                sync_refs[sync] = parse_sync_ref(value)
            except SyncRefError as exc:
                sync_errors[sync] = str(exc)
        else:
            attributes[attr] = value
    text, marks = _text_and_marks(element)
    children = tuple(_node(c) for c in _elements(element) if names.element_name(c.tag) not in MARK_ELEMENTS)
    behaviour_id = element.get("id")
    return Behaviour(element=name, id=(behaviour_id or "").strip(), attributes=attributes, sync_refs=sync_refs,
                     sync_errors=sync_errors, text=text, marks=tuple(marks), children=children, required=required,
                     line=element.sourceline, id_given=bool(behaviour_id and behaviour_id.strip()))


def _node(element) -> Node:
    return Node(names.element_name(element.tag), {names.attribute_name(k): v for k, v in element.attrib.items()},
                (element.text or "").strip(), tuple(_node(c) for c in _elements(element)), element.sourceline)


class _TextBuilder:
    """Collapses white space as text arrives, so mark offsets index the final text."""

    def __init__(self):
        self.text = ""

    def add(self, chunk: str | None) -> None:
        if not chunk:
            return
        chunk = re.sub(r"\s+", " ", chunk)
        if chunk.startswith(" ") and (not self.text or self.text.endswith(" ")):
            chunk = chunk[1:]
        self.text += chunk


def _text_and_marks(element) -> tuple[str | None, list]:
    """Speech text with inline marks: the ``<text>`` child, or the element's own text (SmartBody, draft)."""
    builder, marks = _TextBuilder(), []
    found = [False]

    def walk(node, own_text: bool) -> None:
        if own_text:
            builder.add(node.text)
            found[0] = found[0] or bool((node.text or "").strip())
        for child in node:
            if isinstance(child.tag, str):
                child_name = names.element_name(child.tag)
                if child_name in MARK_ELEMENTS:
                    mark_id = (child.get(MARK_ELEMENTS[child_name]) or child.get("id") or "").strip()
                    if mark_id:
                        marks.append((mark_id, len(builder.text)))
                    found[0] = True
                elif child_name == "text":
                    found[0] = True
                    walk(child, True)
                    builder.add(child.tail)
                    continue
                # Other children (description, prosody markup...) are not spoken; their tails are.
            if own_text:
                builder.add(child.tail)
                found[0] = found[0] or bool((child.tail or "").strip())

    walk(element, True)
    if not found[0]:
        return None, []
    text = builder.text.rstrip()
    return text, [(m, min(offset, len(text))) for m, offset in marks]


def _unique_ids(behaviours: list[Behaviour], block_id: str, issues: list[Issue]) -> list[Behaviour]:
    """Give every behaviour an id: unnamed ones get ``element_N``, a repeated id gets ``id#N`` and a warning."""
    taken = {b.id for b in behaviours if b.id}
    seen: set[str] = set()
    counters: dict[str, int] = {}
    renamed: dict[str, int] = {}
    out = []
    for b in behaviours:
        new_id = b.id
        if not b.id:
            base = b.element.replace(":", "_").replace("{", "").replace("}", "_")
            while True:
                counters[base] = counters.get(base, 0) + 1
                new_id = f"{base}_{counters[base]}"
                if new_id not in taken:
                    break
        elif b.id in seen:
            n = renamed.get(b.id, 1)  # the last suffix given to this id: each rename tries on from there
            while True:
                n += 1
                new_id = f"{b.id}#{n}"
                if new_id not in taken and new_id not in seen:
                    break
            renamed[b.id] = n
            issues.append(Issue(f"{block_id}:{b.id}", PARSING_FAILURE,
                                f"behaviour id {b.id!r} is used twice; this one is renamed {new_id!r}", b.line))
        seen.add(new_id)
        taken.add(new_id)
        out.append(b if new_id == b.id else replace(b, id=new_id))
    return out
