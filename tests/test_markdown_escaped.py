"""Every text that is not the app's own reaches viser markdown through ``markdown.escape``.

Viser renders markdown with raw HTML, unsanitised, so a preset's name, a replay's metadata, a
file name or a refused value echoed into a markdown element could run script in the page.

1. :func:`escape` makes any text show literally: rendered by a CommonMark renderer with raw
   HTML on (as viser's is), the escaped text is one paragraph of plain text, the text itself.
2. A scan of ``src/shoal/app`` (its syntax trees) finds every place markdown content is made
   (``add_markdown(...)``, ``handle.content = ...``, a ``Text(text=...)`` and the functions
   given as a markdown readout: ``status=``, ``compute=``, ``on_snapshot=``) and follows the
   f-strings, ``format`` calls, joins and concatenations that make it, through local names and
   the app's functions they call. Every value interpolated there must be a literal, a constant
   of the code (UPPER_CASE), a number (a numeric format spec or a number helper), markdown made
   the same way (a call of a function that passes this scan) or ``escape(...)``; anything else is
   reported with its file and line.
"""

from __future__ import annotations

import ast
import html
import re
from dataclasses import dataclass, field
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st
from markdown_it import MarkdownIt

import shoal.app
from shoal.app.markdown import JOINER, MAX_SHOWN, escape

APP = Path(shoal.app.__file__).parent
RENDER = MarkdownIt("commonmark", {"html": True}).enable(["table", "strikethrough"])

# ---------------------------------------------------------------------------- 1. the helper
HOSTILE = [
    '<iframe srcdoc="<script>parent.__pwn=1</script>"></iframe>',
    "<img src=x onerror=alert(1)>", "<script>alert(1)</script>", "</p><p onclick=x>",
    "[click](javascript:alert(1))", "![x](http://evil.example/x.png)", "<http://evil.example>",
    "**bold** _it_ `code` ~~s~~", "# heading", "1. list", "- item", "> quote", "| a | b |\n|---|---|",
    "&lt;script&gt;", "&#60;script&#62;", "\\<b>", "line\nbreak\r\n<b>", "a\x00b\x1bc", "x" * 1000,
]


def _plain(rendered: str) -> str:
    """The one paragraph of plain text ``rendered`` must be, unescaped (else AssertionError)."""
    m = re.fullmatch(r"<p>(.*)</p>\n", rendered, flags=re.S)
    assert m is not None, rendered
    assert "<" not in m.group(1), rendered
    return html.unescape(m.group(1))


def _shown(text: str) -> str:
    return re.sub(r"[\x00-\x1f\x7f\u0085\u2028\u2029]+", " ", text)


def _seen(text: str) -> str:
    """What a reader sees of rendered text: the word joiners that break autolinks show nothing."""
    return text.replace(JOINER, "")


def test_escaped_hostile_texts_render_as_themselves():
    for text in HOSTILE:
        out = _plain(RENDER.render(escape(text, limit=None)))
        assert _seen(out) == _shown(text), (text, out)


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet=st.characters(codec="utf-8", exclude_categories=("Cs",)), min_size=1, max_size=60))
def test_any_text_escaped_renders_as_itself(text):
    if not _shown(text).strip():  # only spaces: no paragraph at all
        return
    out = _plain(RENDER.render(escape(text, limit=None)))
    assert _seen(out).strip() == _seen(_shown(text)).strip()  # (ends trimmed)


# GFM's autolink literals as remark-gfm finds them (mdast-util-gfm-autolink-literal: in text nodes,
# after escapes and references are read) and as its tokenizer does (also mailto: and xmpp:).
GFM_URL = re.compile(r"(https?://|www(?=\.))([-.\w]+)([^ \t\r\n]*)", re.I | re.A)
GFM_EMAIL = re.compile(r"([-.\w+]+)@([-\w]+(?:\.[-\w]+)+)", re.A)
GFM_PROTOCOL = re.compile(r"(mailto|xmpp):[-.\w+]+@", re.I | re.A)
ADDRESSES = [
    "https://evil.example", "http://evil.example/x?y=1#z", "HTTPS://EVIL.EXAMPLE", "hTTp://a.b",
    "www.evil.example", "WWW.EVIL.EXAMPLE/path", "(www.evil.example)", "see www.evil.example.", "x www.a.b/c)",
    "student@uni.example", "a.b+c@d-e.f.gh", "mailto:student@uni.example", "xmpp:me@chat.example",
    "<https://evil.example>", "<student@uni.example>", "[x](https://evil.example)", "[x]: https://evil.example",
    "name https://a.example and www.b.example and c@d.example", "https://evil.example/<img src=x>",
    "ftp://files.example", "javascript:alert(1)", "data:text/html,<script>alert(1)</script>",
]


def test_escaped_addresses_match_no_autolink_pattern():
    for text in ADDRESSES:
        seen = _plain(RENDER.render(escape(text, limit=None)))  # the text nodes remark-gfm's transform reads
        assert not GFM_URL.search(seen) and not GFM_EMAIL.search(seen) and not GFM_PROTOCOL.search(seen), (text, seen)
        assert _seen(seen) == text, (text, seen)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.sampled_from(["http", "https", "://", "www", ".", "@", "mailto:", "a", "-", "+", "_", "/", " ",
                                 "example", "org", "\\", "&", "#", "HTTPS", "WwW"]), min_size=1, max_size=20))
def test_no_escaped_text_matches_an_autolink_pattern(parts):
    seen = _plain(RENDER.render(escape("".join(parts), limit=None))) if "".join(parts).strip() else ""
    assert not GFM_URL.search(seen) and not GFM_EMAIL.search(seen) and not GFM_PROTOCOL.search(seen), (parts, seen)


def test_escape_cuts_long_texts():
    assert len(html.unescape(escape("é" * 10_000))) == MAX_SHOWN
    assert escape("abc", limit=2) == "a…"


# ---------------------------------------------------------------------------- 2. the scan
NUMBER_HELPERS = {"fmt", "_num", "int", "len", "round", "float", "abs", "min", "max", "sum"}  # give numbers only
MARKDOWN_KEYWORDS = ("status", "compute", "on_snapshot")  # KindPanel / Text arguments: functions making markdown
MARKDOWN_FIELDS = {"Text": "text", "KindPanel": "export_note"}  # spec fields holding markdown (checked where made)
# Markdown the project writes itself: the shipped teaching notes and lesson/chooser files.
AUTHORED = {"notes_text": "reads the shipped notes/<kind>.md", "lessons/panel.py": "shows the shipped lesson files",
            "legend_html": "the layers' own glyphs and labels, HTML-escaped (the Share page shows it as HTML)",
            "hall/round_view.py": "a round as HTML, every text html.escape-d (test_hall_rounds.py: hostile texts)",
            "status_text": "the lecturer's status line as the lecturer's panel made it (Panel.refresh_status, scanned)",
            "holder_html": "the arena labels' state as JSON in one attribute, html.escape-d (test_class_labels.py: "
                           "hostile texts)"}
NUMERIC_SPEC = re.compile(r"[<>=^]?[+\- ]?#?0?\d*[,_]?(\.\d+)?[bcdeEfFgGnoxX%]$")


@dataclass
class Module:
    path: Path
    tree: ast.Module
    parents: dict[ast.AST, ast.AST] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.path.relative_to(APP).as_posix()


def _modules() -> list[Module]:
    out = []
    for path in sorted(APP.rglob("*.py")):
        mod = Module(path, ast.parse(path.read_text(encoding="utf-8")))
        for node in ast.walk(mod.tree):
            for child in ast.iter_child_nodes(node):
                mod.parents[child] = node
        out.append(mod)
    return out


class Scan:
    def __init__(self) -> None:
        self.modules = _modules()
        self.defs: dict[str, list[tuple[Module, ast.FunctionDef]]] = {}
        for mod in self.modules:
            for node in ast.walk(mod.tree):
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    self.defs.setdefault(node.name, []).append((mod, node))
        self.problems: list[str] = []
        self.callbacks: dict[str, list[tuple[Module, ast.FunctionDef]]] = {}  # keyword → functions given there
        self.sinks = 0
        self._checked: set[int] = set()

    # -------------------------------------------------------------- where markdown is made
    def run(self) -> None:
        for mod in self.modules:
            if mod.name in AUTHORED:
                continue
            for node in ast.walk(mod.tree):
                if isinstance(node, ast.Call) and self._attr(node.func) == "add_markdown":
                    args = list(node.args[:1]) + [k.value for k in node.keywords if k.arg == "content"]
                    for a in args:
                        self._sink(mod, a)
                elif isinstance(node, (ast.Assign, ast.AugAssign)):
                    targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                    if any(isinstance(t, ast.Attribute) and t.attr == "content" for t in targets):
                        self._sink(mod, node.value)
                elif isinstance(node, ast.Call) and self._attr(node.func) in MARKDOWN_FIELDS:
                    for k in node.keywords:
                        if k.arg == MARKDOWN_FIELDS[self._attr(node.func)]:
                            self._sink(mod, k.value)
                if isinstance(node, ast.Call):
                    for k in node.keywords:
                        if k.arg in MARKDOWN_KEYWORDS and isinstance(k.value, ast.Name):
                            fns = [(m, fn) for m, fn in self.defs.get(k.value.id, []) if m is mod]
                            self.callbacks.setdefault(k.arg, []).extend(fns)
                            if not fns:
                                self._report(mod, k.value, "a markdown callback the scan cannot find")
        for fns in self.callbacks.values():
            for m, fn in fns:
                self._returns(m, fn)

    def _sink(self, mod: Module, expr: ast.expr) -> None:
        self.sinks += 1
        self._safe(mod, expr)

    @staticmethod
    def _attr(func: ast.expr) -> str | None:
        return func.attr if isinstance(func, ast.Attribute) else func.id if isinstance(func, ast.Name) else None

    def _report(self, mod: Module, node: ast.AST, what: str) -> None:
        self.problems.append(f"{mod.name}:{getattr(node, 'lineno', '?')}: {what}: {ast.unparse(node)[:100]}")

    def _enclosing(self, mod: Module, node: ast.AST) -> ast.AST | None:
        while node in mod.parents:
            node = mod.parents[node]
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                return node
        return None

    # -------------------------------------------------------------- what is safe
    def _resolve(self, name: str, mod: Module, at: ast.AST) -> list[tuple[Module, ast.FunctionDef]]:
        """The app functions a call of ``name`` at ``at`` may run: a method (``x.name()``) may be
        any of that name; a plain name is the module's own, or the one it imports."""
        found = self.defs.get(name, [])
        if isinstance(at, ast.Call) and isinstance(at.func, ast.Attribute):  # a method, or a markdown callback
            methods = [(m, fn) for m, fn in found if isinstance(m.parents.get(fn), ast.ClassDef)]
            return methods + (self.callbacks.get(name, []) if name in MARKDOWN_KEYWORDS else [])
        own = [(m, fn) for m, fn in found if m is mod]
        if own:
            return own
        for node in ast.walk(mod.tree):
            if isinstance(node, ast.ImportFrom) and any((a.asname or a.name) == name for a in node.names):
                if node.level == 0 and not (node.module or "").startswith("shoal.app"):
                    return []  # from outside the app: its text is not seen
                target = (node.module or "").replace("shoal.app.", "").replace(".", "/")
                return [(m, fn) for m, fn in found if m.name.removesuffix(".py").endswith(target.split("/")[-1])]
        return found

    def _function(self, name: str, mod: Module, at: ast.AST) -> bool:
        """Check the return values of the app functions a call of ``name`` runs; False if none."""
        if name in AUTHORED:
            return True
        found = self._resolve(name, mod, at)
        for fmod, fn in found:
            self._returns(fmod, fn)
        return bool(found)

    def _returns(self, mod: Module, fn: ast.FunctionDef) -> None:
        if id(fn) in self._checked or mod.name in AUTHORED:
            return
        self._checked.add(id(fn))
        for node in ast.walk(fn):
            if isinstance(node, ast.Return) and node.value is not None and self._enclosing(mod, node) is fn:
                self._safe(mod, node.value)

    def _name(self, mod: Module, node: ast.Name) -> None:
        if node.id.isupper() or node.id in ("True", "False", "None"):
            return  # a constant of the code
        fn = self._enclosing(mod, node)
        if fn is None:
            self._report(mod, node, "a module-level name not in UPPER_CASE")
            return
        args = fn.args
        params = {a.arg for a in args.args + args.kwonlyargs + args.posonlyargs}
        if node.id in params:
            self._parameter(mod, fn, node)
            return
        found = False
        for sub in ast.walk(fn):
            if isinstance(sub, ast.Assign) and any(isinstance(t, ast.Name) and t.id == node.id for t in sub.targets):
                found = True
                self._safe(mod, sub.value)
            elif isinstance(sub, ast.Assign) and any(
                    isinstance(t, ast.Tuple) and any(isinstance(e, ast.Name) and e.id == node.id for e in t.elts)
                    for t in sub.targets):
                found = True
                for t in sub.targets:
                    if not isinstance(t, ast.Tuple):
                        continue
                    for i, e in enumerate(t.elts):
                        if isinstance(e, ast.Name) and e.id == node.id:
                            if isinstance(sub.value, ast.Tuple) and len(sub.value.elts) == len(t.elts):
                                self._safe(mod, sub.value.elts[i])
                            else:
                                self._report(mod, node, "a name unpacked from a value (pass it through escape())")
            elif isinstance(sub, ast.AugAssign) and isinstance(sub.target, ast.Name) and sub.target.id == node.id:
                found = True
                self._safe(mod, sub.value)
            elif isinstance(sub, ast.AnnAssign) and isinstance(sub.target, ast.Name) and sub.target.id == node.id:
                found = True
                if sub.value is not None:
                    self._safe(mod, sub.value)
            elif isinstance(sub, ast.NamedExpr) and sub.target.id == node.id:
                found = True
                self._safe(mod, sub.value)
            elif isinstance(sub, (ast.For, ast.comprehension)) and any(
                    isinstance(t, ast.Name) and t.id == node.id for t in ast.walk(sub.target)):
                found = True
                if not self._constant_loop(sub, node.id):
                    self._report(mod, node, "a loop variable (pass it through escape())")
        if not found:
            self._report(mod, node, "a name whose value the scan cannot see")

    def _parameter(self, mod: Module, fn: ast.AST, node: ast.Name) -> None:
        """A parameter is safe if its default and what every call in the app passes are."""
        if isinstance(fn, ast.Lambda):
            self._report(mod, node, "a lambda's parameter (pass it through escape())")
            return
        args = fn.args
        positional = [a.arg for a in args.posonlyargs + args.args]
        method = isinstance(mod.parents.get(fn), ast.ClassDef)
        index = positional.index(node.id) - method if node.id in positional else None
        defaults = dict(zip(positional[len(positional) - len(args.defaults):], args.defaults))
        defaults.update({a.arg: d for a, d in zip(args.kwonlyargs, args.kw_defaults) if d is not None})
        if node.id in defaults:
            self._safe(mod, defaults[node.id])
        names = {fn.name} | {kw for kw, fns in self.callbacks.items() if any(f is fn for _, f in fns)}
        calls = 0
        for cmod in self.modules:
            for call in ast.walk(cmod.tree):
                if not isinstance(call, ast.Call) or self._attr(call.func) not in names:
                    continue
                calls += 1
                given = [k.value for k in call.keywords if k.arg == node.id]
                if index is not None and 0 <= index < len(call.args) and not any(
                        isinstance(a, ast.Starred) for a in call.args[: index + 1]):
                    given.append(call.args[index])
                for value in given:
                    self._safe(cmod, value)
        if not calls:
            self._report(mod, node, "a parameter of a function the app never calls by name")

    @staticmethod
    def _constant_loop(loop: ast.For | ast.comprehension, name: str) -> bool:
        """Does ``name`` take only literal values in ``loop`` (over a literal tuple, or its part of a zip)?"""
        def literal(e: ast.expr) -> bool:
            return isinstance(e, (ast.Tuple, ast.List)) and all(isinstance(x, ast.Constant) for x in e.elts)

        target, it = loop.target, loop.iter
        if isinstance(target, ast.Name):
            return literal(it)
        if (isinstance(target, ast.Tuple) and isinstance(it, ast.Call) and isinstance(it.func, ast.Name)
                and it.func.id == "zip"):
            return any(isinstance(t, ast.Name) and t.id == name and literal(a) for t, a in zip(target.elts, it.args))
        return False

    def _formatted(self, mod: Module, value: ast.FormattedValue) -> None:
        spec = value.format_spec
        if spec is not None and value.conversion == -1:
            text = "".join(v.value for v in spec.values if isinstance(v, ast.Constant))
            if NUMERIC_SPEC.match(text) or (text and not all(isinstance(v, ast.Constant) for v in spec.values)):
                return  # a number format: a string raises there
        if value.conversion in (ord("r"), ord("a")):
            self._report(mod, value, "a repr() of a value (pass it through escape())")
            return
        self._safe(mod, value.value)

    def _safe(self, mod: Module, node: ast.expr) -> None:
        if isinstance(node, ast.Constant):
            return
        if isinstance(node, ast.JoinedStr):
            for v in node.values:
                if isinstance(v, ast.FormattedValue):
                    self._formatted(mod, v)
            return
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Mod)):
            self._safe(mod, node.left)
            if isinstance(node.op, ast.Add):
                self._safe(mod, node.right)
            else:
                self._report(mod, node, "a %-format (use an f-string with escape())")
            return
        if isinstance(node, ast.BinOp):  # numbers: * - / // **
            return
        if isinstance(node, ast.IfExp):
            self._safe(mod, node.body)
            self._safe(mod, node.orelse)
            return
        if isinstance(node, ast.BoolOp):
            for v in node.values:
                self._safe(mod, v)
            return
        if isinstance(node, (ast.Compare, ast.UnaryOp)):
            return  # a bool or a number
        if isinstance(node, ast.Name):
            self._name(mod, node)
            return
        if isinstance(node, ast.Attribute) and node.attr in MARKDOWN_FIELDS.values():
            return  # a spec field holding markdown: checked where the spec is made
        if isinstance(node, ast.Subscript):
            base = node.value
            if isinstance(base, ast.Name) and base.id.isupper() or self._literal_table(base):
                return  # a table of the code
            self._report(mod, node, "an item of a value (pass it through escape())")
            return
        if isinstance(node, (ast.GeneratorExp, ast.ListComp)):
            self._safe(mod, node.elt)
            return
        if isinstance(node, (ast.List, ast.Tuple)):
            for e in node.elts:
                self._safe(mod, e)
            return
        if isinstance(node, ast.Call):
            self._call(mod, node)
            return
        self._report(mod, node, "a value the scan cannot tell is safe (pass it through escape())")

    @staticmethod
    def _ours(mod: Module) -> bool:
        """Does ``escape`` in ``mod`` name the app's helper (not ``html.escape``, say)?"""
        return any(isinstance(n, ast.ImportFrom) and (n.module or "").endswith("markdown")
                   and any(a.name == "escape" and a.asname is None for a in n.names) for n in ast.walk(mod.tree))

    def _local_lambdas(self, mod: Module, call: ast.Call) -> bool:
        """A call of a local name bound to lambdas: their bodies are checked. False if it is not one."""
        fn = self._enclosing(mod, call)
        lambdas: list[ast.Lambda] = []
        for sub in ast.walk(fn) if fn is not None else ():
            if isinstance(sub, ast.Assign) and any(isinstance(t, ast.Name) and t.id == call.func.id
                                                   for t in sub.targets):
                value = sub.value
                options = [value.body, value.orelse] if isinstance(value, ast.IfExp) else [value]
                if not all(isinstance(o, ast.Lambda) for o in options):
                    return False
                lambdas += options
        for lam in lambdas:
            self._safe(mod, lam.body)
        return bool(lambdas)

    @staticmethod
    def _literal_table(node: ast.expr) -> bool:
        return isinstance(node, ast.Name) and node.id.isupper() or (
            isinstance(node, ast.Dict) and all(isinstance(v, ast.Constant) for v in node.values))

    def _call(self, mod: Module, node: ast.Call) -> None:
        name = self._attr(node.func)
        if isinstance(node.func, ast.Name) and (name in NUMBER_HELPERS or name == "escape" and self._ours(mod)):
            return
        if name == "str" and isinstance(node.func, ast.Name):
            for a in node.args:
                self._safe(mod, a)
            return
        if name == "get" and isinstance(node.func, ast.Attribute) and self._literal_table(node.func.value):
            for a in node.args[1:]:  # the default
                self._safe(mod, a)
            return
        if name == "join" and isinstance(node.func, ast.Attribute):
            self._safe(mod, node.func.value)
            for a in node.args:
                self._safe(mod, a)
            return
        if name == "format" and isinstance(node.func, ast.Attribute):
            self._safe(mod, node.func.value)
            for a in [*node.args, *(k.value for k in node.keywords)]:
                self._safe(mod, a)
            return
        if name in ("strip", "rstrip", "lstrip", "upper", "lower", "capitalize", "title") and isinstance(
                node.func, ast.Attribute):
            self._safe(mod, node.func.value)
            return
        if isinstance(node.func, ast.Name) and self._local_lambdas(mod, node):
            return
        if name is not None and self._function(name, mod, node):
            return  # its returns are checked as markdown
        self._report(mod, node, "a call whose text the scan cannot see (pass it through escape())")


def test_no_text_reaches_markdown_without_escape():
    scan = Scan()
    scan.run()
    assert scan.sinks > 30, "the scan found too few markdown elements: has the app's markdown moved?"
    assert not scan.problems, "\n" + "\n".join(sorted(set(scan.problems)))
