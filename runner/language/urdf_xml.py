"""A URDF file as XML: its bytes as pybullet's loader reads them, the lxml tree (every element's line), the
checks of its structure (names, joint types, references, one root), and the text handed to yourdfpy."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from runner.language.model_names import check_names
from runner.language.robot_desc import ModelFileError

#: URDF joint types, as the description's joint kinds
KINDS = {
    "revolute": "hinge",
    "continuous": "hinge",
    "prismatic": "slider",
    "fixed": "fixed",
    "spherical": "ball",  # pybullet's extension (humanoid.urdf): a ball joint at the child's origin
    "floating": "free",  # no joint: the child is a free body, as pybullet and MuJoCo load it
}


def xml_bytes(file: Path) -> bytes:
    """The file's bytes with the quirks pybullet's loader reads past blanked (each byte replaced by a space, so
    lines and columns stay): every XML declaration (pybullet_data declares `version="0.0"`, which XML
    parsers refuse, and two files declare it after a comment or a blank line), and NUL bytes (humanoid.urdf
    ends with one: "Extra content at the end of the document"). docs/robots.md lists them."""

    try:
        raw = file.read_bytes()
    except OSError as exc:
        raise ModelFileError(file, 0, f"cannot read the model file: {exc.strerror}") from None
    blanked = re.sub(rb"<\?xml\s[^>]*\?>", lambda m: b" " * len(m.group(0)), raw.replace(b"\x00", b" "))
    return blanked


def parse_xml(file: Path) -> Any:
    """The lxml tree, or the file and line of the first syntax error."""
    from lxml import etree

    parser = etree.XMLParser(remove_comments=True, resolve_entities=False, no_network=True)
    try:
        return etree.ElementTree(etree.fromstring(xml_bytes(file), parser))
    except etree.XMLSyntaxError as exc:
        line, column = exc.position if exc.position else (exc.lineno or 0, 0)
        raise ModelFileError(file, line or 0, f"malformed XML: {exc.msg}", column=column or 0) from None


#: collision geometry pybullet reads and no engine here simulates, by its tag
_REFUSED_GEOMETRY = {
    "plane": "pybullet's implicit <plane> (the scenario's `plane` body is the ground)",
    "cdf": "pybullet's signed-distance field <cdf>",
}
_XACRO = re.compile(r"\$\((?!optenv\s)|\$\{")


def _check_geometry(tree: Any, file: Path) -> None:
    """Every collision <geometry> is one the loaders read (other elements in a <geometry>, such as the
    <material> racecar.urdf puts there, are read past, as pybullet does), and no xacro expression is left
    (but `$(optenv ...)`)."""
    for geometry in tree.getroot().iterfind("link/collision/geometry"):
        for shape in geometry:
            if isinstance(shape.tag, str) and shape.tag in _REFUSED_GEOMETRY:
                what = _REFUSED_GEOMETRY[shape.tag]
                raise ModelFileError(file, shape.sourceline or 0, f"geometry {what} is not simulated here")
    for element in tree.getroot().iter():
        for key, value in element.attrib.items():
            if _XACRO.search(value):
                raise ModelFileError(
                    file, element.sourceline or 0, f"`{key}` holds a xacro expression {value!r}: run xacro first",
                    near=value,
                )  # fmt: skip


def yourdfpy_text(file: Path) -> bytes:
    """What yourdfpy reads: the file as pybullet reads it. <capsule> becomes <cylinder> (made a capsule again
    from the tree), `$(optenv NAME default)` (xacro, left in husky.urdf) the variable or its default, and
    numbers as pybullet's reader takes them (:func:`_numbers`)."""
    import os

    text = re.sub(rb"<(/?)capsule\b", rb"<\1cylinder", xml_bytes(file))

    def optenv(m: re.Match[bytes]) -> bytes:
        return os.environ.get(m.group(1).decode(), m.group(2).decode()).encode()

    text = re.sub(rb"\$\(optenv\s+(\S+)\s*([^)]*)\)", optenv, text)
    return re.sub(rb'="([-+0-9.eE,\s]*)"', lambda m: b'="' + _numbers(m.group(1)) + b'"', text)


_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _numbers(value: bytes) -> bytes:
    """A list of numbers as pybullet's reader takes it: commas are separators, and each item is its longest
    leading number (strtod: biped2d_pybullet.urdf writes `-1.57.`); an item with none is left to fail."""
    items = value.replace(b",", b" ").split()
    out = []
    for item in items:
        found = _NUMBER.match(item)
        out.append(found.group(0) if found else item)
    return b" ".join(out)


def _lines(tree: Any, tag: str) -> dict[str, int]:
    return {e.get("name"): e.sourceline or 0 for e in tree.getroot().iter(tag) if e.get("name")}


def check_structure(tree: Any, file: Path) -> tuple[dict[str, int], dict[str, int]]:
    """Names and references, with the line of each problem; returns the links' and joints' lines."""

    root = tree.getroot()
    if root.tag != "robot":
        raise ModelFileError(file, root.sourceline or 0, f"expected a <robot> URDF document, found <{root.tag}>")
    for kind in ("link", "joint"):
        check_names(file, kind, [(e.get("name"), e.sourceline or 0) for e in root.findall(kind)])
    links, joints = _lines(tree, "link"), _lines(tree, "joint")
    if not links:
        soft = root.find("deformable")
        if soft is not None:
            what = "a deformable body (pybullet's <deformable>), which no engine here simulates"
            raise ModelFileError(file, soft.sourceline or 0, what)
        raise ModelFileError(file, root.sourceline or 0, "the model has no <link>")
    _check_geometry(tree, file)
    children: dict[str, str] = {}
    for joint in root.iter("joint"):
        line = joint.sourceline or 0
        if joint.getparent() is not root:
            continue  # a <transmission>'s joint reference
        kind = joint.get("type", "")
        if kind not in KINDS:
            raise ModelFileError(
                file,
                line,
                f"joint `{joint.get('name')}` has type `{kind}`, which no engine here simulates"
                f"{' (a planar joint: motion in a plane, on none of the four engines)' if kind == 'planar' else ''}"
                f"; supported: {', '.join(KINDS)}",
            )
        for end in ("parent", "child"):
            element = joint.find(end)
            ref = element.get("link") if element is not None else None
            if ref is None:
                raise ModelFileError(file, line, f"joint `{joint.get('name')}` has no <{end} link=...>")
            if ref not in links:
                where = element.sourceline or line
                raise ModelFileError(
                    file,
                    where,
                    f"joint `{joint.get('name')}` names {end} link `{ref}`, which the model does not define",
                    near=f"<{end}",
                )
        child = joint.find("child").get("link")
        if child in children:
            raise ModelFileError(file, line, f"link `{child}` is the child of two joints (`{children[child]}` too)")
        children[child] = str(joint.get("name"))
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise ModelFileError(file, root.sourceline or 0, f"expected one root link, found {roots or 'none (a loop)'}")
    return links, joints


def find_capsules(tree: Any) -> set[tuple[str, int]]:
    """(link, index of its <collision>) of every capsule: pybullet's extension, radius and length (the
    cylinder between the two half-spheres' centres) along the local z, as our capsule."""
    found = set()
    for link in tree.getroot().iter("link"):
        for k, collision in enumerate(link.findall("collision")):
            if collision.find("geometry/capsule") is not None:
                found.add((str(link.get("name")), k))
    return found


def mesh_file_lines(tree: Any) -> dict[str, int]:
    return {e.get("filename"): e.sourceline or 0 for e in tree.getroot().iter("mesh") if e.get("filename")}
