"""Element and attribute names as infuse writes them, whatever namespace the document used.

BML 1.0, the pre-1.0 draft namespace, the BML 1.0 core extensions and no namespace at all (SmartBody)
all mean the core vocabulary: their elements are named by their local name (``"head"``). Elements of
a namespace with a well-known prefix are named ``"prefix:local"`` (``"sbm:reach"``, ``"bmlt:blinkemitter"``);
any other namespace gives Clark notation ``"{uri}local"``. Attributes follow the same rule.
"""
from __future__ import annotations

#: The BML 1.0 namespace.
BML_NS = "http://www.bml-initiative.org/bml/bml-1.0"
#: The namespace of the pre-1.0 BML draft (used by Greta).
BML_DRAFT_NS = "http://www.mindmakers.org/projects/BML"
#: The BML 1.0 core extensions (``faceFacs``...).
BML_EXT_NS = "http://www.bml-initiative.org/bml/coreextensions-1.0"
#: The namespace SmartBody's own parser binds to the ``sbm:`` prefix.
SBM_NS = "http://ict.usc.edu"
#: infuse's own namespace: block attributes that turn BML generators on (``infuse:nonverbal="true"``).
INFUSE_NS = "urn:infuse:bml"
#: Prefixes found undeclared in a document are bound to this URI plus the prefix.
UNDECLARED_NS = "urn:infuse:undeclared-prefix:"

#: Namespaces whose elements are the core vocabulary.
CORE_NAMESPACES = frozenset({"", BML_NS, BML_DRAFT_NS, BML_EXT_NS})

#: Well-known extension namespaces and the prefix infuse names them with.
KNOWN_PREFIXES: dict[str, str] = {
    SBM_NS: "sbm",
    "http://hmi.ewi.utwente.nl/bmlt": "bmlt",
    "http://www.asap-project.org/bmla": "bmla",
    "http://asap-project.org/convanim": "convanim",
    "http://hmi.ewi.utwente.nl/stomprosnaoengine": "srne",
    "VIBNameSpace": "greta",
    INFUSE_NS: "infuse",
}
_URI_OF_PREFIX = {prefix: uri for uri, prefix in KNOWN_PREFIXES.items()}


def split_clark(tag: str) -> tuple[str, str]:
    """``"{uri}local"`` -> ``(uri, local)``; a name without namespace gives ``("", name)``."""
    if tag.startswith("{"):
        uri, _, local = tag[1:].partition("}")
        return uri, local
    return "", tag


def prefix_of(uri: str) -> str | None:
    """The prefix infuse uses for ``uri``, or None for an unknown namespace."""
    if uri in KNOWN_PREFIXES:
        return KNOWN_PREFIXES[uri]
    if uri.startswith(UNDECLARED_NS):
        return uri[len(UNDECLARED_NS):]
    return None


def element_name(tag: str) -> str:
    """The infuse name of an element from its lxml tag (Clark notation)."""
    uri, local = split_clark(tag)
    if uri in CORE_NAMESPACES:
        return local
    prefix = prefix_of(uri)
    return f"{prefix}:{local}" if prefix else tag


def attribute_name(key: str) -> str:
    """The infuse name of an attribute from its lxml key: no namespace stays plain, otherwise as elements."""
    uri, local = split_clark(key)
    if not uri:
        return local
    if uri in CORE_NAMESPACES:
        return local
    prefix = prefix_of(uri)
    return f"{prefix}:{local}" if prefix else key


def normalize_name(name: str) -> str:
    """A name a plugin wrote (``"head"``, ``"sbm:reach"``, ``"{uri}local"``) in the form the parser produces."""
    if name.startswith("{"):
        return element_name(name)
    prefix, sep, local = name.partition(":")
    if sep and prefix in _URI_OF_PREFIX:
        return f"{prefix}:{local}"
    return name
