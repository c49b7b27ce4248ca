"""The C preprocessor subset Marlin's configuration headers use, evaluated three-valued.

:class:`Headers` reads files in order (``Configuration.h`` then ``Configuration_adv.h``, as
Marlin includes them): comments, ``\\`` line continuations, ``#define`` (object- and
function-like), ``#undef``, ``#if``/``#ifdef``/``#ifndef``/``#elif``/``#else``/``#endif`` and
``#error``. Conditions are C integer expressions with ``defined``, Marlin's ``ENABLED()``,
``DISABLED()``, ``ANY()``, ``ALL()``, ``BOTH()``, ``EITHER()``, ``NONE()``, and macros that
name other macros (expanded, with a depth bound).

A condition that depends on something the files do not define (``MOTHERBOARD == BOARD_X`` when
the board's number is Marlin's, ``HAS_…``) is *undecidable*: its branches are all kept, each
definition made inside remembers the conditions it depends on, and a name defined differently
in such branches has several :meth:`Headers.candidates` — the reader says which figure depends
on which branch, never picks one silently. ``ENABLED(X)`` is Marlin's: X defined as nothing,
``1``, ``0x1`` or ``true``.

Bounds: each line is read once; expansion stops at :data:`_MAX_DEPTH` levels and
:data:`_MAX_TOKENS` tokens; numbers have at most 40 digits and shifts at most 64 bits (beyond
that a value is unknown, never computed).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from fractions import Fraction
from itertools import islice

from wavecheck.firmware._text import where

__all__ = ["Definition", "Headers", "Num", "evaluate"]

_MAX_DEPTH = 32
_MAX_TOKENS = 4096
_MAX_DIGITS = 40
_TOKEN = re.compile(
    r"\s*(?:(?P<num>(?:0[xX][0-9a-fA-F]+|\d+\.?\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)"
    r"[uUlLfF]*)|(?P<id>[A-Za-z_]\w*)|(?P<str>\"(?:[^\"\\]|\\.)*\"|'(?:[^'\\]|\\.)*')"
    r"|(?P<op>&&|\|\||<<|>>|<=|>=|==|!=|[-+*/%<>!~&|^?:(),{}\[\]]))"
)
_DIRECTIVE = re.compile(r"^\s*#\s*(\w+)\s*(.*)$")
_ENABLED = {"", "1", "0x1", "true"}
#: Names whose different spellings are different constants (Marlin's board and driver numbers).
_UNIQUE = re.compile(r"BOARD_\w+|(?:A4988|A5984|DRV8825|LV8729|L64\d\d|TB6560|TB6600|TMC\w+)\Z")


@dataclass(frozen=True)
class Num:
    """A C number: an exact value and whether C holds it as an integer."""

    value: Fraction
    integer: bool


Value = Num | str | None
"""A number, a symbolic constant the files do not define (its name), or None (unknown)."""


@dataclass(frozen=True)
class Definition:
    """One ``#define`` (or ``#undef``: ``value`` None) and where it was made.

    Attributes:
        name: the macro.
        value: its replacement text (comments removed), None for ``#undef``.
        params: the parameter names of a function-like macro, None otherwise.
        where: ``file:line``.
        depends: the undecidable conditions (``#if … at file:line``) it was made under.
    """

    name: str
    value: str | None
    params: tuple[str, ...] | None
    where: str
    depends: tuple[str, ...] = ()
    order: int = field(default=0, compare=False)
    """The order definitions were read in."""


@dataclass
class _Branch:
    outer: bool | None  # is the enclosing region live?
    taken: bool | None  # has an earlier branch of this #if been taken?
    this: bool | None  # is this branch's condition true?
    why: str  # the condition, for depends
    start: int = 0  # Headers._order when the #if was read
    arms: list[set[str] | None] = field(default_factory=list)  # names each arm defines (None: dead)
    has_else: bool = False

    @property
    def live(self) -> bool | None:
        return _and(self.outer, self.this)


def _and(a: bool | None, b: bool | None) -> bool | None:
    if a is False or b is False:
        return False
    if a is None or b is None:
        return None
    return True


def _or(a: bool | None, b: bool | None) -> bool | None:
    if a is True or b is True:
        return True
    if a is None or b is None:
        return None
    return False


def _not(a: bool | None) -> bool | None:
    return None if a is None else not a


@dataclass
class Headers:
    """The macros of some C headers read in order (see the module doc)."""

    defs: dict[str, list[Definition]] = field(default_factory=dict)
    errors: list[str] = field(default_factory=list)
    files: list[str] = field(default_factory=list)
    functions: dict[str, Callable[[list[str]], bool | None]] = field(default_factory=dict)
    """Function-like names the reader answers itself (Marlin's ``HAS_DRIVER(TMC2209)``): the
    argument words → True, False or None (undecidable)."""
    _order: int = 0

    def predefine(self, name: str, value: str, where: str) -> None:
        """Define ``name`` as a header the files include would (Marlin's derived
        ``HAS_…`` macros)."""
        self._set(Definition(name, value, None, where))

    def feed(self, path: str, text: str) -> None:
        """Read one file's text (its directives; other lines are ignored)."""
        self.files.append(path)
        stack: list[_Branch] = []
        for no, line in _logical_lines(text):
            m = _DIRECTIVE.match(line)
            if not m:
                continue
            word, rest = m.group(1), m.group(2).strip()
            at = where(path, no)
            live = stack[-1].live if stack else True
            if word in ("if", "ifdef", "ifndef"):
                cond = (
                    self.truth(rest)
                    if word == "if"
                    else (self._defined(rest.split()[0]) if rest else None)
                )
                if word == "ifndef":
                    cond = _not(cond)
                b = _Branch(live, cond, cond, f"#{word} {rest} at {at}", self._order)
                b.arms.append(None if cond is False else set())
                stack.append(b)
            elif word in ("elif", "else") and stack:
                b = stack[-1]
                if word == "elif":
                    cond = (
                        self.truth(rest) if b.outer is not False and b.taken is not True else False
                    )
                    b.this = _and(_not(b.taken), cond)
                    b.taken = _or(b.taken, cond)
                    b.why = f"#elif {rest} at {at}"
                else:
                    b.this = _not(b.taken)
                    b.taken, b.has_else = True, True
                    b.why = f"#else at {at} (of {b.why})"
                b.arms.append(None if b.this is False else set())
            elif word == "endif" and stack:
                self._close(stack.pop(), stack)
            elif live is False:
                continue
            elif word in ("define", "undef") and rest:
                if word == "define":
                    self._define(rest, at, self._depends(stack))
                else:
                    self._set(Definition(rest.split()[0], None, None, at, self._depends(stack)))
                arm = stack[-1].arms[-1] if stack else None
                if arm is not None:
                    arm.add(rest.split("(")[0].split()[0])
            elif word == "error" and live:
                self.errors.append(f"{at}: #error {rest}")

    def _close(self, b: _Branch, stack: list[_Branch]) -> None:
        """At ``#endif``: a name every possible arm of an undecidable ``#if … #else`` chain
        defines no longer keeps the definitions made before the chain."""
        arms = [a for a in b.arms if a is not None]
        if not (b.has_else and b.outer is True and arms and len(arms) > 1):
            return
        everywhere = set.intersection(*arms)
        for name in everywhere:
            self.defs[name] = [d for d in self.defs.get(name, []) if d.order > b.start]
        outer_arm = stack[-1].arms[-1] if stack else None
        if outer_arm is not None:
            outer_arm.update(everywhere)

    @staticmethod
    def _depends(stack: list[_Branch]) -> tuple[str, ...]:
        return tuple(b.why for b in stack if b.this is None or b.outer is None)

    def _define(self, rest: str, at: str, depends: tuple[str, ...]) -> None:
        m = re.match(r"([A-Za-z_]\w*)(\(([^)]*)\))?\s*(.*)$", rest, re.S)
        if not m:
            return
        params = None
        if m.group(2) is not None:
            params = tuple(p.strip() for p in m.group(3).split(",") if p.strip())
        self._set(Definition(m.group(1), m.group(4).strip(), params, at, depends))

    def _set(self, d: Definition) -> None:
        self._order += 1
        d = replace(d, order=self._order)
        if d.depends:
            current = self.defs.setdefault(d.name, [])
            if not current:
                current.append(Definition(d.name, None, None, "not defined", ()))
            current.append(d)
        else:
            self.defs[d.name] = [d]

    def candidates(self, name: str) -> list[Definition]:
        """Every definition ``name`` may have at the end (``value`` None: not defined); one
        when the files decide it, none when they never mention it."""
        return list(self.defs.get(name, []))

    def definition(self, name: str) -> Definition | None:
        """The one definition of ``name`` when the files decide it (None when undefined or
        undecidable: see :meth:`candidates`)."""
        c = self.defs.get(name, [])
        return c[0] if len(c) == 1 and c[0].value is not None else None

    def _defined(self, name: str) -> bool | None:
        c = self.defs.get(name)
        if not c:
            return False
        states = {d.value is not None for d in c}
        return states.pop() if len(states) == 1 else None

    def enabled(self, name: str) -> bool | None:
        """Marlin's ``ENABLED(name)``: defined as nothing, 1, 0x1 or true (None: undecidable)."""
        c = self.defs.get(name)
        if not c:
            return False
        states: set[bool | None] = set()
        for d in c:
            if d.value is None or d.params is not None:
                states.add(False)
                continue
            tokens = self.expand(d.value)
            text = " ".join(t for _, t in tokens)
            states.add(None if any(k == "unk" for k, _ in tokens) else text in _ENABLED)
        return states.pop() if len(states) == 1 else None

    def truth(self, expr: str) -> bool | None:
        """A ``#if`` condition: True, False or None (undecidable)."""
        v = evaluate(self, expr)
        if isinstance(v, Num):
            return v.value != 0
        return None

    def expand(
        self, text: str, depth: int = 0, busy: frozenset[str] = frozenset()
    ) -> list[tuple[str, str]]:
        """``text``'s tokens with object-like macros replaced (a macro with several candidate
        values becomes an ``unk`` token); ``defined``/``ENABLED``… arguments are kept as
        written."""
        out: list[tuple[str, str]] = []
        tokens = list(islice(_tokens(text), _MAX_TOKENS + 1))
        if len(tokens) > _MAX_TOKENS:
            return [_UNKNOWN]
        i = 0
        while i < len(tokens):
            kind, tok = tokens[i]
            if len(out) > _MAX_TOKENS or depth > _MAX_DEPTH:
                return [_UNKNOWN]
            if kind == "id" and (tok == "defined" or tok in _FUNCTIONS):
                end = _skip_call(tokens, i) if tok != "defined" else _skip_defined(tokens, i)
                out += tokens[i:end]
                i = end
                continue
            if kind == "id" and tok not in busy and tok in self.defs:
                c = self.defs[tok]
                if len(c) == 1 and c[0].value is not None and c[0].params is None:
                    out += self.expand(c[0].value, depth + 1, busy | {tok})
                elif len(c) > 1:
                    out.append(_UNKNOWN)
                else:
                    out.append((kind, tok))
                i += 1
                continue
            out.append((kind, tok))
            i += 1
        return out


_UNKNOWN = ("unk", "?")
#: C++ functional casts Marlin's configurations use: name → makes a floating value.
_CASTS = {"double": True, "float": True, "int": False, "long": False, "uint32_t": False,
          "int32_t": False}  # fmt: skip
_FUNCTIONS = {
    "ENABLED",
    "DISABLED",
    "ANY",
    "ALL",
    "BOTH",
    "EITHER",
    "NONE",
    "TERN",
    "TERN0",
    "TERN1",
}


def _skip_call(tokens: list[tuple[str, str]], i: int) -> int:
    if i + 1 >= len(tokens) or tokens[i + 1][1] != "(":
        return i + 1
    depth = 0
    for j in range(i + 1, len(tokens)):
        if tokens[j][1] == "(":
            depth += 1
        elif tokens[j][1] == ")":
            depth -= 1
            if depth == 0:
                return j + 1
    return len(tokens)


def _skip_defined(tokens: list[tuple[str, str]], i: int) -> int:
    if i + 1 < len(tokens) and tokens[i + 1][1] == "(":
        return min(i + 4, len(tokens))
    return min(i + 2, len(tokens))


def _logical_lines(text: str) -> Iterator[tuple[int, str]]:
    """(first line number, text) of each logical line: block and line comments removed,
    ``\\`` continuations joined."""
    buf: list[str] = []
    start, in_block = 0, False
    for no, raw in enumerate(text.splitlines(), 1):
        line, in_block = _strip_comments(raw, in_block)
        if not buf:
            start = no
        if line.endswith("\\"):
            buf.append(line[:-1])
            continue
        buf.append(line)
        yield start, " ".join(buf)
        buf = []
    if buf:
        yield start, " ".join(buf)


def _strip_comments(line: str, in_block: bool) -> tuple[str, bool]:
    out: list[str] = []
    i = 0
    while i < len(line):
        if in_block:
            end = line.find("*/", i)
            if end < 0:
                return "".join(out).rstrip(), True
            i, in_block = end + 2, False
            out.append(" ")
            continue
        j = _next_comment(line, i)
        if j < 0:
            out.append(line[i:])
            break
        out.append(line[i:j])
        if line.startswith("//", j):
            break
        in_block, i = True, j + 2
    return "".join(out).rstrip(), in_block


def _next_comment(line: str, i: int) -> int:
    quote = ""
    for j in range(i, len(line) - 1):
        ch = line[j]
        if quote:
            if ch == "\\":
                continue
            if ch == quote:
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch == "/" and line[j + 1] in "/*":
            return j
    return -1


def _tokens(text: str) -> Iterator[tuple[str, str]]:
    pos = 0
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            if text[pos:].strip():
                yield _UNKNOWN
            return
        pos = m.end()
        kind = m.lastgroup or "op"
        yield kind, m.group(kind)


def _number(tok: str) -> Num | None:
    t = tok.rstrip("uUlLfF") if not tok.lower().startswith("0x") else tok.rstrip("uUlL")
    if len(t.replace(".", "")) > _MAX_DIGITS + 6:
        return None
    try:
        if t.lower().startswith("0x"):
            return Num(Fraction(int(t, 16)), True)
        if re.fullmatch(r"0[0-7]+", t):
            return Num(Fraction(int(t, 8)), True)
        is_int = re.fullmatch(r"\d+", t) is not None
        m = re.search(r"[eE]([-+]?\d+)$", t)
        if m and abs(int(m.group(1))) > _MAX_DIGITS:
            return None
        return Num(Fraction(t), is_int)
    except (ValueError, ZeroDivisionError):
        return None


class _Parser:
    """Precedence climbing over expanded tokens (C's precedence and integer division)."""

    _BINARY = {
        "||": 1, "&&": 2, "|": 3, "^": 4, "&": 5, "==": 6, "!=": 6,
        "<": 7, ">": 7, "<=": 7, ">=": 7, "<<": 8, ">>": 8,
        "+": 9, "-": 9, "*": 10, "/": 10, "%": 10,
    }  # fmt: skip

    def __init__(self, headers: Headers, tokens: list[tuple[str, str]]) -> None:
        self.h = headers
        self.t = tokens
        self.i = 0

    def peek(self) -> str:
        return self.t[self.i][1] if self.i < len(self.t) else ""

    def take(self) -> tuple[str, str]:
        tok = self.t[self.i] if self.i < len(self.t) else ("op", "")
        self.i += 1
        return tok

    def expr(self, level: int = 0) -> Value:
        left = self.unary()
        while True:
            op = self.peek() if self.i < len(self.t) and self.t[self.i][0] == "op" else ""
            if op == "?" and level == 0:
                self.take()
                yes = self.expr()
                if self.peek() != ":":
                    return None
                self.take()
                no = self.expr()
                cond = _bool(left)
                return (
                    yes if cond is True else no if cond is False else (yes if yes == no else None)
                )
            prec = self._BINARY.get(op)
            if prec is None or prec <= level:
                return left
            self.take()
            right = self.expr(prec)
            left = _binary(op, left, right)

    def unary(self) -> Value:
        kind, tok = self.take()
        if tok == "(":
            v = self.expr()
            if self.peek() == ")":
                self.take()
            return v
        if tok in ("!", "-", "+", "~"):
            v = self.unary()
            if not isinstance(v, Num):
                return None
            if tok == "!":
                return Num(Fraction(int(v.value == 0)), True)
            if tok == "-":
                return Num(-v.value, v.integer)
            if tok == "~":
                return Num(Fraction(~int(v.value)), True) if v.integer else None
            return v
        if kind == "num":
            return _number(tok)
        if kind == "unk":
            return None
        if kind == "id":
            if tok == "defined":
                name = self.take()[1]
                if name == "(":
                    name = self.take()[1]
                    self.take()
                return _tri(self.h._defined(name))
            if tok in _FUNCTIONS:
                return self.call(tok)
            if tok in _CASTS and self.peek() == "(":
                self.take()
                inner = self.expr()
                if self.peek() == ")":
                    self.take()
                if not isinstance(inner, Num):
                    return None
                if _CASTS[tok]:
                    return Num(inner.value, False)
                whole = abs(inner.value.numerator) // inner.value.denominator
                return Num(Fraction(whole if inner.value >= 0 else -whole), True)
            if tok in ("true", "false"):
                return Num(Fraction(int(tok == "true")), True)
            if self.peek() == "(":
                end = _skip_call(self.t, self.i - 1)
                args = [
                    " ".join(t for _, t in a) for a in _split_args(self.t[self.i + 1 : end - 1])
                ]
                self.i = end
                fn = self.h.functions.get(tok)
                return _tri(fn(args)) if fn else None  # others: not evaluated
            return tok  # a constant the files do not define
        return None

    def call(self, fn: str) -> Value:
        if self.peek() != "(":
            return None
        end = _skip_call(self.t, self.i - 1)
        inner = self.t[self.i + 1 : end - 1]
        self.i = end
        if fn.startswith("TERN"):
            return self._tern(fn, _split_args(inner))
        names = [t for k, t in inner if k == "id"]
        states = [self.h.enabled(n) for n in names]
        if fn == "DISABLED":
            states = [_not(s) for s in states]
        result: bool | None
        if fn in ("ENABLED", "DISABLED", "ALL", "BOTH"):
            result = True
            for s in states:
                result = _and(result, s)
        elif fn in ("ANY", "EITHER"):
            result = False
            for s in states:
                result = _or(result, s)
        else:  # NONE
            result = True
            for s in states:
                result = _and(result, _not(s))
        return _tri(result)

    def _tern(self, fn: str, args: list[list[tuple[str, str]]]) -> Value:
        """Marlin's ``TERN(O, A, B)`` (A if ENABLED(O) else B), ``TERN0``/``TERN1`` (else 0/1)."""
        if not args or len(args[0]) != 1:
            return None
        other = {"TERN0": [("num", "0")], "TERN1": [("num", "1")]}.get(fn)
        choices = args[1:3] if other is None else [*args[1:2], other]
        if len(choices) != 2:
            return None
        cond = self.h.enabled(args[0][0][1])
        values = [evaluate(self.h, " ".join(t for _, t in c)) for c in choices]
        if cond is None:
            return values[0] if values[0] == values[1] else None
        return values[0] if cond else values[1]


def _split_args(tokens: list[tuple[str, str]]) -> list[list[tuple[str, str]]]:
    args: list[list[tuple[str, str]]] = [[]]
    depth = 0
    for kind, tok in tokens:
        if tok in "({" and kind == "op":
            depth += 1
        elif tok in ")}" and kind == "op":
            depth -= 1
        if tok == "," and depth == 0:
            args.append([])
        else:
            args[-1].append((kind, tok))
    return args


def _tri(b: bool | None) -> Value:
    return None if b is None else Num(Fraction(int(b)), True)


def _bool(v: Value) -> bool | None:
    return v.value != 0 if isinstance(v, Num) else None


def _binary(op: str, a: Value, b: Value) -> Value:
    if op in ("&&", "||"):
        p, q = _bool(a), _bool(b)
        return _tri(_and(p, q) if op == "&&" else _or(p, q))
    if op in ("==", "!=") and isinstance(a, str) and isinstance(b, str):
        if a == b:
            same: bool | None = True
        elif _UNIQUE.match(a) and _UNIQUE.match(b):
            same = False
        else:
            same = None
        return _tri(same if op == "==" else _not(same))
    if not isinstance(a, Num) or not isinstance(b, Num):
        return None
    x, y, integer = a.value, b.value, a.integer and b.integer
    if op in ("<", ">", "<=", ">=", "==", "!="):
        result = {"<": x < y, ">": x > y, "<=": x <= y, ">=": x >= y, "==": x == y, "!=": x != y}
        return Num(Fraction(int(result[op])), True)
    if op in ("+", "-", "*"):
        v = x + y if op == "+" else x - y if op == "-" else x * y
        return Num(v, integer) if abs(v) < 10**60 else None
    if op in ("/", "%"):
        if y == 0:
            return None
        if integer:  # C truncates toward zero, and the remainder takes the dividend's sign
            quot = abs(x.numerator) // abs(y.numerator)
            quot = quot if (x < 0) == (y < 0) else -quot
            return Num(Fraction(quot) if op == "/" else x - quot * y, True)
        return Num(x / y, False) if op == "/" else None
    if not integer:
        return None
    ix, iy = int(x), int(y)
    if op in ("<<", ">>"):
        if not 0 <= iy <= 64:
            return None
        return Num(Fraction(ix << iy if op == "<<" else ix >> iy), True)
    return Num(Fraction(ix & iy if op == "&" else ix | iy if op == "|" else ix ^ iy), True)


def evaluate(headers: Headers, text: str) -> Value:
    """``text`` (a ``#if`` condition or a macro's value) as a number, a symbolic constant, or
    None when it cannot be decided or is not one expression."""
    tokens = headers.expand(text)
    parser = _Parser(headers, tokens)
    try:
        v = parser.expr()
    except RecursionError:
        return None
    return v if parser.i >= len(tokens) else None
