"""Griffe extension of the API reference (mkdocs.yml): hcomc's docstrings read as written.

hcomc's docstrings are numpy-style with Sphinx markup. Before griffe parses one, this
extension rewrites its text (the source files are not touched) where griffe's numpy parser or
Markdown would read it otherwise than meant:

* ``name : prose`` in an item section, where the text after the colon is not a type (not a
  Python expression), is a description, and the type comes from the signature's annotation;
  in ``Returns`` / ``Yields`` a bare line that is not a type describes the return value;
* a paragraph after a blank line in a ``Parameters`` / ``Attributes`` / ``Modules`` section
  that does not start like an item is prose about all the items: it goes into a ``Notes``
  section instead of being read as more items;
* in a ``Modules`` section an item ``:mod:`hcomc.pkg.sub``` becomes ``sub``, the name griffe
  looks the submodule up by;
* Sphinx roles (``:class:`~hcomc.x.Y```, ``:func:``, ``:mod:``, ...) become cross-references:
  to an hcomc object the reference shows, a link; to one that exists but is not shown, its
  name as code; to an hcomc object that does not exist, a warning, so that a stale reference
  fails the ``--strict`` build; to another library's object, its name as code (the build
  stays offline);
* reStructuredText that Markdown does not know: simple tables become Markdown tables,
  ``:math:`` and ``.. math::`` become MathJax input, citations ``.. [1]`` a list, and the
  ``::`` before a literal block a colon;
* ``[t0, t1] [s]`` (an interval and its unit) would be a Markdown reference link: the second
  bracket is escaped;
* a pydantic field's ``Field(description=...)`` becomes its docstring (and leaves the
  ``Field(...)`` the signature shows).
"""

from __future__ import annotations

import ast
import builtins
import functools
import html
import re
from pathlib import Path
from typing import Any

import griffe

PACKAGE = "hcomc"
ROLE = re.compile(
    r":(?:py:)?(?P<role>class|func|meth|attr|mod|data|obj|exc|const|type):`(?P<body>[^`]+)`"
)
NAME = r"\*{0,2}[A-Za-z_]\w*"
ITEM = re.compile(rf"^(?P<names>{NAME}(?:,\s*{NAME})*)(?:\s*:\s*(?P<rest>.*))?$")
RETURN_NAMED = re.compile(rf"^(?P<names>{NAME}(?:,\s*{NAME})*)\s+:\s+(?P<rest>.*)$")
MODULE = re.compile(r"^[A-Za-z_][\w.]*(\(.*\))?$")
ITEM_SECTIONS = {"parameters", "other parameters", "attributes"}
RETURN_SECTIONS = {"returns", "yields", "receives"}
TUPLES = {"tuple", "typing.Tuple", "Tuple"}
TABLE_BORDER = re.compile(r"^\s*=+( +=+)+\s*$")
MATH_BLOCK = re.compile(r"^(?P<indent>\s*)\.\. math::\s*(?P<first>.*)$")
MATH_ROLE = re.compile(r":math:`(?P<body>[^`]+)`")
CITATION = re.compile(r"^(?P<indent>\s*)\.\. \[(?P<label>\w+)\]\s+(?P<rest>.*)$")
UNIT_AFTER_BRACKET = re.compile(r"\]\s\[")
NOTES = ["Notes", "-----"]


# --- numpy sections ---------------------------------------------------------------------


def _is_dash_line(line: str) -> bool:
    return "-" in line and not line.replace("-", "").strip()


def _is_type(text: str) -> bool:
    """Whether the text after ``name :`` reads as a type (``int``, ``dict or None``,
    ``numpy.ndarray, shape (n,)``, ``float, optional``) rather than a sentence."""
    text = re.sub(r",\s*(optional|default[ :=].*)$", "", text.strip())
    if not text:
        return True
    try:
        ast.parse(text, mode="eval")
    except SyntaxError:
        return False
    return True


def _return_types(obj: griffe.Object, start: int, width: int, count: int) -> str | None:
    """The type of the return item that names tuple positions ``start`` to ``start + width``
    of a section of ``count`` items, from the signature; None when it does not say. (griffe's
    own lookup assumes one position per item and fails on ``tuple[T, ...]``.)"""
    annotation = getattr(obj, "returns", None) if obj.is_function else None
    if annotation is None:
        return None
    if count == 1:
        return str(annotation)
    if not (isinstance(annotation, griffe.ExprSubscript) and str(annotation.left) in TUPLES):
        return None
    inner = annotation.slice
    elements = [str(e) for e in inner.elements] if isinstance(inner, griffe.ExprTuple) else []
    if elements[1:] == ["..."]:
        return ", ".join([elements[0]] * width)
    if start + width <= len(elements):
        return ", ".join(elements[start : start + width])
    return None


class _Sections:
    """The line-by-line rewrite of one docstring's numpy sections."""

    def __init__(self, obj: griffe.Object, lines: list[str]) -> None:
        self.obj, self.lines = obj, lines
        self.section: str | None = None
        self.items_seen = False
        self.n_items = self.position = 0

    def start(self, title: str, first: int) -> None:
        self.section, self.items_seen, self.position = title.strip().lower(), False, 0
        self.n_items = 0
        for i in range(first, len(self.lines)):
            line = self.lines[i]
            if i + 1 < len(self.lines) and line.strip() and _is_dash_line(self.lines[i + 1]):
                break
            self.n_items += bool(line.strip()) and not line.startswith(" ")

    def item(self, line: str, after_blank: bool) -> list[str]:
        """An unindented line of the current section, rewritten."""
        if self.section in ITEM_SECTIONS:
            return self._parameter(line, after_blank)
        if self.section in RETURN_SECTIONS:
            return self._return(line)
        if self.section == "modules":
            return self._module(line, after_blank)
        return [line]

    def _notes(self, line: str) -> list[str]:
        self.section = "notes"
        return [*NOTES, line]

    def _parameter(self, line: str, after_blank: bool) -> list[str]:
        match = ITEM.match(line)
        closing = match is None and after_blank and self.items_seen
        self.items_seen = True
        if closing:
            return self._notes(line)
        if match is not None and match["rest"] and not _is_type(match["rest"]):
            return [match["names"], f"    {match['rest']}"]
        return [line]

    def _return(self, line: str) -> list[str]:
        named = RETURN_NAMED.match(line)
        names, prose = (named["names"].split(","), named["rest"]) if named else ([], line)
        width = len(names) or 1
        kind = _return_types(self.obj, self.position, width, self.n_items)
        self.position += width
        if _is_type(prose):
            return [line]
        if kind is None and getattr(self.obj, "returns", None) is not None:
            return [line]  # griffe would look the type up in the signature and fail
        head = names[0] if len(names) == 1 else ""
        text = prose if len(names) <= 1 else line
        return [f"{head} : {kind}".strip() if kind else f"{head} :".strip(), f"    {text}"]

    def _module(self, line: str, after_blank: bool) -> list[str]:
        role = ROLE.fullmatch(line.strip())
        closing = role is None and after_blank and self.items_seen and not MODULE.match(line)
        self.items_seen = True
        if closing:
            return self._notes(line)
        return [role["body"].lstrip("~").rsplit(".", 1)[-1] if role else line]


def normalise_sections(text: str, obj: griffe.Object) -> str:
    """The docstring with its numpy sections in the form griffe reads (see the module
    docstring); everything else unchanged."""
    lines = text.split("\n")
    sections = _Sections(obj, lines)
    out: list[str] = []
    in_fence = False
    for i, line in enumerate(lines):
        fence = line.lstrip().startswith("```")
        in_fence ^= fence
        following = lines[i + 1] if i + 1 < len(lines) else ""
        if in_fence or fence:
            out.append(line)
        elif line.strip() and _is_dash_line(following) and not _is_dash_line(line):
            sections.start(line, i + 2)
            out.append(line)
        elif not line.strip() or line.startswith(" ") or _is_dash_line(line):
            out.append(line)
        else:
            out.extend(sections.item(line, i > 0 and not lines[i - 1].strip()))
    return "\n".join(out)


# --- cross-references ---------------------------------------------------------------------


@functools.cache
def _module_names(filepath: Path) -> frozenset[str]:
    """Names a module binds at its top level, including those griffe does not record as
    members (``VR, VMC = range(2)``)."""
    names: set[str] = set()
    for node in ast.parse(filepath.read_text(encoding="utf-8")).body:
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", None)]
        for target in targets:
            for sub in ast.walk(target) if target is not None else ():
                if isinstance(sub, ast.Name):
                    names.add(sub.id)
    return frozenset(names)


def _binds(module: griffe.Object, name: str) -> bool:
    if name in (module.exports or ()):
        return True  # also a name served lazily by the module's __getattr__
    filepath = module.filepath
    return isinstance(filepath, Path) and name in _module_names(filepath)


def _get(loader: griffe.GriffeLoader, path: str) -> griffe.Object | griffe.Alias | None:
    try:
        return loader.modules_collection[path]
    except (KeyError, ValueError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return None


def _exists(loader: griffe.GriffeLoader, path: str, *, attribute: bool) -> bool:
    """Whether the object exists: a member griffe found, a name its module binds otherwise,
    or an attribute of an existing class set outside ``__init__`` (which static analysis
    does not see)."""
    if _get(loader, path) is not None:
        return True
    parent = _get(loader, path.rpartition(".")[0])
    if parent is None:
        return False
    if parent.is_module:
        return _binds(parent, path.rpartition(".")[2])
    return attribute and parent.is_class


def _resolve(obj: griffe.Object, target: str, role: str) -> str | None:
    """The full path of a role's target as written in ``obj``'s docstring: a name in the
    scope of ``obj`` or its module, or an attribute of the enclosing class."""
    head, _, tail = target.lstrip(".").partition(".")
    owner: griffe.Object | None = obj
    while owner is not None and not owner.is_class:
        owner = owner.parent
    try:
        found = obj.resolve(head)
    except griffe.NameResolutionError:
        if _binds(obj.module, head):
            found = f"{obj.module.path}.{head}"
        elif owner is not None and _inherits(owner, head):
            found = f"{owner.path}.{head}"
        elif owner is not None and role == "attr" and not tail:
            found = f"{owner.path}.{head}"  # an attribute set outside __init__
        else:
            return None
    return f"{found}.{tail}" if tail else found


def _inherits(cls: griffe.Object, name: str) -> bool:
    try:
        return name in cls.all_members
    except (griffe.AliasResolutionError, griffe.CyclicAliasError, KeyError):
        return False


def rewrite_roles(
    obj: griffe.Object, text: str, loader: griffe.GriffeLoader, *, strict: bool = True
) -> str:
    """Sphinx roles as cross-references (see the module docstring); ``strict``: a reference
    to an hcomc object that does not exist is a warning, else only logged at debug level."""
    report = griffe.logger.warning if strict else griffe.logger.debug

    def replace(match: re.Match[str]) -> str:
        body = re.sub(r"\s+", " ", match["body"]).strip()
        explicit = re.fullmatch(r"(?P<title>.+?)\s*<(?P<target>[^>]+)>", body)
        if explicit:
            title, target = explicit["title"], explicit["target"].replace(" ", "")
        else:
            target = body.lstrip("~").replace(" ", "")
            title = target.rsplit(".", 1)[-1] if body.startswith("~") else target
        if match["role"] in {"func", "meth"} and not title.endswith(")"):
            title = f"{title}()"
        code = f"<code>{html.escape(title)}</code>"
        if target.split(".")[0] == PACKAGE:
            path: str | None = target
        else:
            path = _resolve(obj, target, match["role"])
        if path is None:
            if "." not in target and not hasattr(builtins, target):
                report("%s: %s names '%s', which is not in scope", obj.path, match[0], target)
            return code  # a dotted name out of scope: another library's (numpy.ndarray, ...)
        if path.split(".")[0] != PACKAGE:
            return code  # another library's object (numpy, matplotlib, gymnasium, ...)
        if not _exists(loader, path, attribute=match["role"] == "attr"):
            report("%s: %s names '%s', which does not exist", obj.path, match[0], path)
            return code
        return f'<autoref identifier="{path}" optional>{code}</autoref>'

    return ROLE.sub(replace, text)


# --- reStructuredText ---------------------------------------------------------------------


def _indent(line: str) -> int:
    return len(line) - len(line.lstrip())


def _simple_table(lines: list[str], start: int) -> tuple[list[str], int] | None:
    """The RST simple table whose top border is ``lines[start]`` as a Markdown table, and the
    index after it; None if there is no closing border."""
    spans = [m.start() for m in re.finditer(r"=+", lines[start])]
    indent = lines[start][: _indent(lines[start])]
    rows: list[list[str]] = []
    header: list[str] | None = None
    for i in range(start + 1, len(lines)):
        line = lines[i]
        if TABLE_BORDER.match(line):
            if header is None and rows and i + 1 < len(lines) and lines[i + 1].strip():
                header, rows = [" ".join(cell) for cell in zip(*rows, strict=True)], []
                continue
            head = header or [""] * len(spans)
            table = [head, ["---"] * len(spans), *rows]
            escaped = ([c.replace("|", "\\|") for c in row] for row in table)
            return [f"{indent}| {' | '.join(row)} |" for row in escaped], i + 1
        if not line.strip():
            continue
        ends = [*spans[1:], len(line)]
        row = [line[a:b].strip() for a, b in zip(spans, ends, strict=True)]
        if rows and not row[0]:  # continuation of the previous row
            rows[-1] = [f"{a} {b}".strip() for a, b in zip(rows[-1], row, strict=True)]
        else:
            rows.append(row)
    return None


def _math_block(lines: list[str], start: int) -> tuple[list[str], int]:
    match = MATH_BLOCK.match(lines[start])
    assert match is not None
    indent, body = match["indent"], [match["first"]]
    i = start + 1
    while i < len(lines) and (not lines[i].strip() or _indent(lines[i]) > len(indent)):
        if not lines[i].strip().startswith(":label:"):
            body.append(lines[i].strip())
        i += 1
    body = [f"{indent}{b}" for b in body if b]
    return ["", f"{indent}$$", *body, f"{indent}$$", ""], i


def _literal_marker(line: str) -> str:
    """``text::`` before a literal block reads ``text:``; a lone ``::`` disappears."""
    text = line.rstrip()[:-2]
    return f"{text.rstrip()}:" if text.strip() and not text.endswith(" ") else text.rstrip()


def rst_to_markdown(text: str) -> str:
    """The reStructuredText Markdown does not read, as Markdown (see the module docstring)."""
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        table = _simple_table(lines, i) if TABLE_BORDER.match(line) else None
        citation = CITATION.match(line)
        if table is not None:
            out.extend(table[0])
            i = table[1]
            continue
        if MATH_BLOCK.match(line):
            block, i = _math_block(lines, i)
            out.extend(block)
            continue
        if citation:
            line = f"{citation['indent']}- [{citation['label']}] {citation['rest']}"
        elif line.rstrip().endswith("::") and i + 1 < len(lines) and not lines[i + 1].strip():
            line = _literal_marker(line)
        out.append(line)
        i += 1
    return MATH_ROLE.sub(lambda m: f"\\({m['body']}\\)", "\n".join(out))


def escape_unit_brackets(text: str) -> str:
    """``[t0, t1] [s]`` with the second bracket escaped, outside code."""
    lines = text.split("\n")
    in_fence = False
    for i, line in enumerate(lines):
        fence = line.lstrip().startswith("```")
        in_fence ^= fence
        if in_fence or fence or line.lstrip().startswith((">>>", "...")):
            continue
        parts = line.split("`")
        parts[::2] = [UNIT_AFTER_BRACKET.sub(r"] \\[", part) for part in parts[::2]]
        lines[i] = "`".join(parts)
    return "\n".join(lines)


# --- pydantic fields ----------------------------------------------------------------------


def field_docstring(attr: griffe.Object) -> griffe.Docstring | None:
    """A pydantic field's ``Field(description=...)`` as a docstring; a nested table
    (``Field(default_factory=RoadParams)``) named as such; None for anything else."""
    value = getattr(attr, "value", None)
    if attr.parent is None or not attr.parent.is_class or not isinstance(value, griffe.ExprCall):
        return None
    if str(value.function).rsplit(".", 1)[-1] != "Field":
        return None
    keywords = {a.name: a.value for a in value.arguments if isinstance(a, griffe.ExprKeyword)}
    if "description" in keywords:
        try:
            text = ast.literal_eval(str(keywords["description"]))
        except (ValueError, SyntaxError):
            return None
        # the docstring says it: the signature shows the default and the bounds
        value.arguments = [a for a in value.arguments if getattr(a, "name", "") != "description"]
    elif "default_factory" in keywords:
        text = f"The ``[{attr.name}]`` table: :class:`{keywords['default_factory']}`."
    else:
        return None
    return griffe.Docstring(str(text), parent=attr)


class HcomcDocstrings(griffe.Extension):
    """Rewrites every docstring of hcomc once the package is loaded.

    ``strict_references`` (an option in mkdocs.yml, default true): a Sphinx role naming an
    hcomc object that does not exist is a warning, which fails ``mkdocs build --strict``.
    """

    def __init__(self, strict_references: bool = True) -> None:
        super().__init__()
        self.strict_references = strict_references

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        if pkg.name != PACKAGE:
            return
        stack: list[griffe.Object] = [pkg]
        while stack:
            obj = stack.pop()
            if obj.docstring is None and obj.is_attribute:
                obj.docstring = field_docstring(obj)
            if obj.docstring is not None:
                text = rst_to_markdown(normalise_sections(obj.docstring.value, obj))
                text = rewrite_roles(obj, text, loader, strict=self.strict_references)
                obj.docstring.value = escape_unit_brackets(text)
                obj.docstring.__dict__.pop("parsed", None)  # parse the new text
            stack.extend(m for m in obj.members.values() if not m.is_alias)
