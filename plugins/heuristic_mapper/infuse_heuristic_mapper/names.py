"""What a joint's name says: normalized tokens, the side, body-part roles and warning flags.

Names are a hint only (hierarchy and geometry decide); they break ties and recognise joints that
are not part of the body (IK targets, control bones, props, hair).

Normalization: the namespace (``mixamorig:``), known rig prefixes (``Bip01``, ``CC_Base_``,
``DEF-``, ``J_Bip_``...) and the prefix shared by nearly all names are stripped; the rest is
split at camelCase, digits, ``_``, ``.``, ``-`` and spaces, and known words written together
(``leftarm``, ``ARMCONTROL``) are split. Common CJK body words are translated; a few Spanish,
French, German and Portuguese body and side words are known.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

#: Word -> body-part role. Roles are matched per token after lower-casing and compound joining.
ROLE_WORDS: dict[str, str] = {
    # pelvis / hips
    "hips": "hips", "pelvis": "hips", "pelvic": "hips", "cog": "hips", "com": "hips",
    # torso
    "spine": "spine", "back": "spine", "lowerback": "spine", "upperback": "spine", "abdomen": "spine",
    "abdomen2": "spine", "waist": "spine", "torso": "spine", "stomach": "spine", "belly": "spine",
    "lowerspine": "spine", "middlespine": "spine", "upperbody": "spine", "lumbar": "spine",
    "chest": "chest", "upperchest": "chest", "thorax": "chest", "ribcage": "chest", "ribs": "chest",
    # neck / head / eyes
    "neck": "neck", "lowerneck": "neck", "upperneck": "neck", "cervical": "neck",
    "head": "head", "skull": "head", "skullbase": "head", "cranium": "head",
    "eye": "eye", "eyes": "eye", "eyeball": "eye", "eyeballs": "eye",
    # arm
    "clavicle": "clavicle", "collar": "clavicle", "collarbone": "clavicle", "clav": "clavicle",
    "sternoclavicular": "clavicle", "acromioclavicular": "clavicle", "scapula": "clavicle",
    "shoulder": "shoulder", "shldr": "upperarm",
    "upperarm": "upperarm", "uparm": "upperarm", "humerus": "upperarm", "bicep": "upperarm", "arm": "upperarm",
    "forearm": "forearm", "lowerarm": "forearm", "elbow": "forearm", "ulna": "forearm", "radius": "forearm",
    "lowarm": "forearm",
    "hand": "hand", "wrist": "hand", "palm": "palm",
    # fingers
    "thumb": "thumb", "pollex": "thumb", "index": "index", "pointer": "index", "middle": "middle", "mid": "middle",
    "ring": "ring", "pinky": "pinky", "pinkie": "pinky", "little": "pinky", "small": "pinky",
    "finger": "finger", "fingers": "finger", "digit": "finger",
    # leg
    "thigh": "thigh", "upleg": "thigh", "upperleg": "thigh", "femur": "thigh", "hip": "hip",
    "shin": "shin", "calf": "shin", "lowerleg": "shin", "knee": "shin", "tibia": "shin", "crus": "shin",
    "leg": "leg", "foot": "foot", "ankle": "foot", "tarsal": "foot",
    "toe": "toe", "toes": "toe", "toebase": "toe", "ball": "toe", "forefoot": "toe",
    # Spanish, French, German and Portuguese words that mean nothing else in a rig
    "cadera": "hips", "bassin": "hips", "becken": "hips", "quadril": "hips", "columna": "spine",
    "colonne": "spine", "wirbelsaeule": "spine", "pecho": "chest", "poitrine": "chest", "brust": "chest",
    "cuello": "neck", "cou": "neck", "hals": "neck", "pescoco": "neck", "cabeza": "head", "tete": "head",
    "kopf": "head", "cabeca": "head", "hombro": "shoulder", "epaule": "shoulder", "schulter": "shoulder",
    "ombro": "shoulder", "brazo": "upperarm", "bras": "upperarm", "oberarm": "upperarm", "braco": "upperarm",
    "antebrazo": "forearm", "avantbras": "forearm", "unterarm": "forearm", "antebraco": "forearm",
    "mano": "hand", "muslo": "thigh", "cuisse": "thigh", "oberschenkel": "thigh",
    "coxa": "thigh", "pierna": "shin", "jambe": "shin", "unterschenkel": "shin", "canela": "shin", "pie": "foot",
    "pied": "foot", "fuss": "foot", "dedo": "finger", "doigt": "finger", "pulgar": "thumb",
    "pouce": "thumb", "daumen": "thumb", "polegar": "thumb", "indice": "index", "zeigefinger": "index",
    # Japanese words written in Latin letters
    "mune": "chest", "kubi": "neck", "atama": "head", "hiji": "forearm", "tekubi": "hand", "hiza": "shin",
}

#: Word -> flag for joints that are not (or not only) body joints.
FLAG_WORDS: dict[str, str] = {
    "end": "end", "nub": "end", "top": "end", "tip": "tip", "headtop": "end", "site": "end",
    "twist": "twist", "roll": "twist", "twst": "twist",
    "ik": "control", "fk": "control", "ctrl": "control", "control": "control", "controller": "control",
    "pole": "control", "target": "control", "mch": "control", "org": "control", "snap": "control",
    "track": "control", "cursor": "control", "master": "control", "locator": "control", "goal": "control",
    "orient": "control", "tracker": "control", "effector": "control", "eff": "control", "aim": "control",
    "helper": "helper", "dummy": "helper", "null": "helper", "aux": "helper", "free": "helper",
    "hipjoint": "helper", "buttock": "helper", "fingerbase": "helper", "adjust": "helper", "correct": "helper",
    # anatomical landmarks and sensors (markers, not joints)
    "landmark": "helper", "marker": "helper", "imu": "helper", "sensor": "helper", "acromion": "helper",
    "styloid": "helper", "epicondyle": "helper", "malleolus": "helper", "metatarsal": "helper",
    "occiput": "helper", "sellion": "helper", "vertex": "helper", "sitbone": "helper", "trochanter": "helper",
    "slot": "prop", "weapon": "prop", "sword": "prop", "shield": "prop", "gun": "prop", "prop": "prop",
    "handle": "prop", "sheath": "prop", "helmet": "prop", "attach": "prop", "socket": "prop", "grip": "prop",
    "hair": "secondary", "skirt": "secondary", "bust": "secondary", "breast": "secondary", "sec": "secondary",
    "cloth": "secondary", "cape": "secondary", "coat": "secondary", "tail": "secondary", "ribbon": "secondary",
    "wing": "secondary", "wings": "secondary", "hind": "secondary", "pectoral": "secondary", "fin": "secondary",
    "feather": "secondary", "antenna": "secondary",
    "suso": "secondary", "kami": "secondary", "sode": "secondary", "shippo": "secondary",
    "hood": "secondary", "sleeve": "secondary", "tie": "secondary", "physics": "secondary", "dyn": "secondary",
    "jaw": "face", "chin": "face", "lip": "face", "lips": "face", "cheek": "face", "brow": "face", "eyebrow": "face",
    "lid": "face", "eyelid": "face", "tongue": "face", "nose": "face", "ear": "face", "teeth": "face",
    "mouth": "face", "oris": "face", "levator": "face", "orbicularis": "face", "oculi": "face", "risorius": "face",
    "temporalis": "face", "special": "face", "face": "face", "facial": "face", "lash": "face",
    "metacarpal": "metacarpal", "carpal": "metacarpal", "inhand": "metacarpal",
    "heel": "heel", "root": "root", "ground": "root", "armature": "root", "scene": "root", "rig": "root",
}

#: Tokens that say the joint is on the character's left (+1) or right (-1).
SIDE_WORDS: dict[str, int] = {"l": 1, "left": 1, "lf": 1, "lft": 1, "lt": 1, "links": 1, "gauche": 1, "izq": 1,
                              "izquierdo": 1, "izquierda": 1, "esquerdo": 1, "esquerda": 1,
                              "r": -1, "right": -1, "rt": -1, "rgt": -1, "rechts": -1, "droite": -1, "der": -1,
                              "derecho": -1, "derecha": -1, "direito": -1, "direita": -1}

#: Pairs of adjacent tokens that form one word ("Fore" + "Arm").
COMPOUNDS: dict[tuple[str, str], str] = {
    ("fore", "arm"): "forearm", ("upper", "arm"): "upperarm", ("lower", "arm"): "lowerarm", ("up", "arm"): "uparm",
    ("low", "arm"): "lowarm", ("up", "leg"): "upleg", ("upper", "leg"): "upperleg", ("lower", "leg"): "lowerleg",
    ("low", "leg"): "lowerleg", ("toe", "base"): "toebase", ("head", "top"): "headtop", ("lower", "back"): "lowerback",
    ("upper", "back"): "upperback", ("upper", "chest"): "upperchest", ("finger", "base"): "fingerbase",
    ("lower", "neck"): "lowerneck", ("upper", "neck"): "upperneck", ("hip", "joint"): "hipjoint",
    ("eye", "ball"): "eyeball", ("eye", "lid"): "eyelid", ("eye", "brow"): "eyebrow", ("collar", "bone"): "collarbone",
    ("lower", "spine"): "lowerspine", ("middle", "spine"): "middlespine", ("in", "hand"): "inhand",
    ("skull", "base"): "skullbase", ("fore", "foot"): "forefoot", ("upper", "body"): "upperbody",
    ("lower", "body"): "hips",
}

#: Single words glued to a side letter in some conventions (ASF ``lhumerus``, Daz ``lShldr``).
_GLUED = sorted({w for w in list(ROLE_WORDS) + ["hipjoint", "buttock", "collar", "shldr", "eye", "fingers"] if len(w) >= 3},
                key=len, reverse=True)

#: Known rig prefixes (lower case, matched at the start of the name after the namespace).
RIG_PREFIXES = ("bip01", "bip001", "bip02", "cc_base_", "def-", "def_", "j_bip_", "mixamorig", "valvebiped.bip01_",
                "b_", "bn_", "jnt_", "jt", "bone_", "skeleton_", "sk_", "rig_", "c_")

#: CJK words (Japanese MMD / Chinese rigs) and what they mean, longest first.
CJK_WORDS: tuple[tuple[str, str], ...] = tuple(sorted({
    "左": " left ", "右": " right ", "下半身": " hips ", "上半身2": " chest ", "上半身": " spine ", "センター": " root ",
    "首": " neck ", "頭": " head ", "両目": " eyes ", "目": " eye ", "肩": " clavicle ", "腕": " arm ", "ひじ": " elbow ",
    "肘": " elbow ", "手首": " wrist ", "手": " hand ", "親指": " thumb ", "人指": " index ", "人差指": " index ",
    "中指": " middle ", "薬指": " ring ", "小指": " pinky ", "足首": " ankle ", "ひざ": " knee ", "膝": " knee ",
    "足": " leg ", "つま先": " toe end ", "捩": " twist ", "ＩＫ": " ik ", "先": " end ",
    "骨盆": " pelvis ", "臀部": " hips ", "脊椎": " spine ", "腰": " spine ", "胸": " chest ", "颈": " neck ", "头": " head ",
    "眼": " eye ", "锁骨": " clavicle ", "上臂": " upperarm ", "大臂": " upperarm ", "前臂": " forearm ", "小臂": " forearm ",
    "手腕": " wrist ", "拇指": " thumb ", "食指": " index ", "无名指": " ring ", "大腿": " thigh ", "小腿": " shin ",
    "脚踝": " ankle ", "脚": " foot ", "脚趾": " toe ", "趾": " toe ", "髋": " hips ",
}.items(), key=lambda kv: -len(kv[0])))

_CAMEL = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|\d+")
_SPLIT = re.compile(r"[^0-9A-Za-z]+")


@dataclass(frozen=True)
class NameInfo:
    """What one joint name says.

    - ``tokens``: normalized lower-case tokens (side tokens removed, compounds joined).
    - ``side``: +1 the character's left, -1 right, 0 not stated.
    - ``roles``: body-part roles named (e.g. ``{"forearm"}``); ``flags``: warnings (``"twist"``, ``"end"``...).
    - ``numbers``: the numbers in the name, in order (finger segments, spine order).
    """

    tokens: tuple[str, ...]
    side: int
    roles: frozenset[str]
    flags: frozenset[str]
    numbers: tuple[int, ...]
    role_bits: int = 0  # the roles and flags as bit sets (see :func:`bits`), for array tests
    flag_bits: int = 0

    def has(self, role: str) -> bool:
        return role in self.roles

    def flagged(self, *flags: str) -> bool:
        return not self.flags.isdisjoint(flags)


def _translate_cjk(name: str) -> str:
    if all(ord(c) < 0x2E80 for c in name):
        return name
    for word, meaning in CJK_WORDS:
        name = name.replace(word, meaning)
    return name


def _raw_tokens(name: str) -> list[str]:
    out: list[str] = []
    for part in _SPLIT.split(name):
        out.extend(m.group(0) for m in _CAMEL.finditer(part))
    return out


def strip_namespace(name: str) -> str:
    """``mixamorig:Hips`` -> ``Hips``; ``Armature|Hips`` -> ``Hips``."""
    for sep in (":", "|"):
        if sep in name:
            tail = name.rsplit(sep, 1)[1]
            if tail:
                name = tail
    return name


def common_prefix(names: list[str]) -> str:
    """The prefix (ending at a separator or a case change) shared by at least 90% of the names."""
    if len(names) < 3:
        return ""
    stripped = [strip_namespace(n) for n in names]
    counts: dict[str, int] = {}
    for n in stripped:
        for m in re.finditer(r"[_ .\-:]|(?<=[a-z0-9])(?=[A-Z])", n):
            cut = m.end()
            if 1 <= cut < len(n):
                counts[n[:cut]] = counts.get(n[:cut], 0) + 1
    best = ""
    for prefix, count in counts.items():
        if count >= 0.9 * len(stripped) and len(prefix) > len(best):
            best = prefix
    return best


_BITS: dict[str, int] = {}


def bits(words) -> int:
    """A bit set of role or flag words (each word gets its own bit on first use)."""
    out = 0
    for w in words:
        b = _BITS.get(w)
        if b is None:
            if len(_BITS) >= 62:  # the vocabulary is fixed; this guards the int64 arrays built from it
                raise ValueError("too many distinct role and flag words")
            b = _BITS[w] = 1 << len(_BITS)
        out |= b
    return out


_KNOWN = frozenset(ROLE_WORDS) | frozenset(FLAG_WORDS) | frozenset(SIDE_WORDS)
_SIDE_AFFIXES = tuple(w for w in SIDE_WORDS if len(w) >= 4)  # "left", "right", "links", "gauche"...


def _split_glued(token: str) -> tuple[str, ...]:
    """A token of known words written together without a case change or separator -> the words:
    a side word in front or behind (``leftarm``, ``rightupleg``, ``brasgauche``) and two body or
    warning words (``ARMCONTROL``, ``legorient``); any other token as it is."""
    if len(token) < 6 or token in _KNOWN:
        return (token,)
    for side in _SIDE_AFFIXES:
        if token.startswith(side) and len(token) - len(side) >= 3:
            return (side,) + _split_glued(token[len(side):])
        if token.endswith(side) and len(token) - len(side) >= 3:
            return _split_glued(token[:-len(side)]) + (side,)
    for cut in range(3, len(token) - 2):
        head, tail = token[:cut], token[cut:]
        if (head in ROLE_WORDS or head in FLAG_WORDS) and (tail in ROLE_WORDS or tail in FLAG_WORDS):
            return head, tail
    return (token,)


@lru_cache(maxsize=8192)
def analyse(name: str, prefix: str = "") -> NameInfo:
    """The :class:`NameInfo` of one joint name, with ``prefix`` (shared by the skeleton's names) removed."""
    text = strip_namespace(name)
    helper = text.startswith("_")  # "__LeftShoulder": an internal helper joint
    text = text.lstrip("_")
    if prefix and text.startswith(prefix) and len(text) > len(prefix):
        text = text[len(prefix):]
        helper = helper or text.startswith("_")  # "rig___LeftShoulder" behind a shared prefix
        text = text.lstrip("_") or text
    low = text.lower()
    for rig in RIG_PREFIXES:
        if low.startswith(rig) and len(low) > len(rig):
            # keep "Jt" style prefixes only when they are followed by a capital or separator
            nxt = text[len(rig)]
            if rig in ("jt", "c_", "b_", "bn_", "sk_") and not (nxt.isupper() or not nxt.isalpha()):
                continue
            text = text[len(rig):]
            break
    text = _translate_cjk(text)
    raw = [part for t in _raw_tokens(text) for part in _split_glued(t.lower())]
    side = 0
    tokens: list[str] = []
    numbers: list[int] = []
    for t in raw:
        if t.isdigit():
            numbers.append(int(t))
            continue
        if t in SIDE_WORDS:
            side = side or SIDE_WORDS[t]
            continue
        if t[0] in "lr" and len(t) > 3 and t not in ROLE_WORDS and t not in FLAG_WORDS:
            rest = t[1:]
            if rest in _GLUED or rest in FLAG_WORDS:  # ASF "lhumerus", CMU "lhipjoint"
                side = side or (1 if t[0] == "l" else -1)
                t = rest
        tokens.append(t)
    joined: list[str] = []
    i = 0
    while i < len(tokens):
        pair = tuple(tokens[i:i + 2])
        if len(pair) == 2 and pair in COMPOUNDS:
            joined.append(COMPOUNDS[pair])
            i += 2
        else:
            joined.append(tokens[i])
            i += 1
    roles = {ROLE_WORDS[t] for t in joined if t in ROLE_WORDS}
    flags = {FLAG_WORDS[t] for t in joined if t in FLAG_WORDS}
    # "hip" names the thigh when a side is given (LeftHip, lhip) and the pelvis otherwise (Hip, hip)
    if "hip" in roles:
        roles.discard("hip")
        roles.add("thigh" if side else "hips")
    # "leg": the thigh with "up"/"upper", otherwise the shin (Mixamo LeftLeg), unless numbered first
    if "leg" in roles:
        roles.discard("leg")
        roles.add("legpart")
    if roles & {"hips"} and len(roles) > 1 and {"com", "cog"} & set(joined):
        roles.discard("hips")  # the centre of mass of a segment (COM_LeftForeArm): a marker
        helper = True
    if helper:
        flags.add("helper")
    if "end" in flags and "toe" in roles:
        roles.add("toe_end")
    return NameInfo(tuple(joined), side, frozenset(roles), frozenset(flags), tuple(numbers),
                    bits(roles), bits(flags))


@lru_cache(maxsize=256)
def analyse_all(names: tuple[str, ...]) -> tuple[NameInfo, ...]:
    """:func:`analyse` of every name of a skeleton, with their shared prefix removed (cached: many
    files share one skeleton)."""
    prefix = common_prefix(list(names))
    return tuple(analyse(n, prefix) for n in names)
