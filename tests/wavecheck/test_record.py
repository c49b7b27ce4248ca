"""wavecheck.record: a record class behaves as the dataclass of the same declaration (issue 38:
the record types of ``check`` and ``wavecheck drives`` cost no generated code at start-up, their
API unchanged). Each pair below is declared twice, once with each decorator, and compared."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import pickle
from collections.abc import Callable
from typing import Any, ClassVar

import pytest

from wavecheck import record as record_module
from wavecheck.record import field, field_names, record, replace


def _pair(frozen: bool, eq: bool = True) -> tuple[type, type]:
    """The same class made by ``dataclass`` and by ``record``."""

    def make(decorator: Callable[..., Any], fld: Callable[..., Any]) -> type:
        @decorator(frozen=frozen, eq=eq)
        class Probe:
            """A probe."""

            x: int
            y: str = "a"
            z: dict[str, int] = fld(default_factory=dict)
            k: ClassVar[int] = 3

            def __post_init__(self) -> None:
                self.z.setdefault("made", 1)

        return Probe

    return make(dataclasses.dataclass, dataclasses.field), make(record, field)


CASES = [(True, True), (False, True), (True, False), (False, False)]
IDS = ["frozen", "mutable", "frozen-no-eq", "mutable-no-eq"]


@pytest.mark.parametrize(("frozen", "eq"), CASES, ids=IDS)
def test_a_record_looks_like_its_dataclass(frozen: bool, eq: bool) -> None:
    dc, rc = _pair(frozen, eq)
    assert str(inspect.signature(rc)) == str(inspect.signature(dc))
    assert repr(rc(1)) == repr(dc(1))
    assert repr(rc(1)).endswith(".Probe(x=1, y='a', z={'made': 1})")
    assert rc.__match_args__ == dc.__match_args__ == ("x", "y", "z")
    assert rc.k == 3 and rc.y == "a" and not hasattr(rc, "z")
    assert rc.__init__.__qualname__ == dc.__init__.__qualname__
    assert (rc(1) == rc(1)) is eq and rc(1) != rc(2)
    assert (rc(1) == dc(1)) is False  # another class
    assert (rc.__hash__ is None) == (dc.__hash__ is None)
    if frozen and eq:  # the hash of the fields' tuple, as the dataclass's
        with pytest.raises(TypeError, match="unhashable type: 'dict'"):
            hash(rc(1))
        rc_pair = record(frozen=True)(
            type("Pair", (), {"__annotations__": {"a": "int", "b": "int"}})
        )
        dc_pair = dataclasses.dataclass(frozen=True)(
            type("Pair", (), {"__annotations__": {"a": "int", "b": "int"}, "__module__": __name__})
        )
        assert hash(rc_pair(1, 2)) == hash(dc_pair(1, 2)) == hash((1, 2))
    assert rc(1).z is not rc(1).z  # a fresh dict each


@pytest.mark.parametrize(("frozen", "eq"), CASES, ids=IDS)
def test_a_record_refuses_what_its_dataclass_refuses(frozen: bool, eq: bool) -> None:
    dc, rc = _pair(frozen, eq)
    for bad in ((), (1, "a", {}, 4)):
        with pytest.raises(TypeError) as want:
            dc(*bad)
        with pytest.raises(TypeError) as got:
            rc(*bad)
        assert str(got.value) == str(want.value)
    with pytest.raises(TypeError, match="unexpected keyword argument 'w'"):
        rc(1, w=2)
    obj = rc(1)
    if frozen:
        with pytest.raises(dataclasses.FrozenInstanceError, match="cannot assign to field 'x'"):
            obj.x = 2
        with pytest.raises(dataclasses.FrozenInstanceError, match="cannot delete field 'x'"):
            del obj.x
    else:
        obj.x = 2
        assert obj.x == 2


@pytest.mark.parametrize(("frozen", "eq"), CASES, ids=IDS)
def test_dataclasses_introspection_works_on_a_record(frozen: bool, eq: bool) -> None:
    dc, rc = _pair(frozen, eq)
    assert dataclasses.is_dataclass(rc) and dataclasses.is_dataclass(rc(1))
    fields = [(f.name, f.type, f.default, f.default_factory) for f in dataclasses.fields(rc)]
    assert fields == [
        (f.name, f.type, f.default, f.default_factory) for f in dataclasses.fields(dc)
    ]
    assert rc.__dataclass_params__.frozen is frozen and rc.__dataclass_params__.eq is eq
    assert dataclasses.asdict(rc(1, "b")) == dataclasses.asdict(dc(1, "b"))
    assert dataclasses.astuple(rc(1)) == (1, "a", {"made": 1})
    for copied in (dataclasses.replace(rc(1), y="q"), replace(rc(1), y="q")):
        assert type(copied) is rc and (copied.x, copied.y) == (1, "q")
    assert replace(dc(1), y="q").y == "q"  # a dataclass: dataclasses.replace
    assert copy.deepcopy(rc(1)).x == 1


@record(frozen=True)
class Point:
    """Module level: picklable."""

    x: int
    y: dict[str, int] = field(default_factory=dict)


def test_a_record_pickles() -> None:
    assert pickle.loads(pickle.dumps(Point(1, {"a": 2}))) == Point(1, {"a": 2})


def test_records_of_one_width_share_one_compiled_template() -> None:
    """One ``__init__`` code compiled per number of fields, renamed for each class."""
    n = 61  # a width no record of the project has
    ns = {"__annotations__": {f"f{k}": "int" for k in range(n)}, "__module__": __name__}
    wide = record(frozen=True)(type("Wide", (), ns))
    other = record(type("Other", (), {**ns, "__annotations__": {f"g{k}": "int" for k in range(n)}}))
    obj = wide(*range(n))
    assert obj.f0 == 0 and getattr(obj, f"f{n - 1}") == n - 1
    assert str(inspect.signature(wide)).startswith("(f0: 'int', f1: 'int'")
    assert other(*range(n)).g3 == 3
    assert wide.__init__.__code__.co_code == other.__init__.__code__.co_code
    assert record_module._TEMPLATES[n].co_varnames[:2] == ("self", "a0")


def test_records_inherit_their_bases_fields() -> None:
    @record(frozen=True)
    class Base:
        a: int
        b: int = 2

    @record(frozen=True)
    class Child(Base):
        c: int = 3

    assert repr(Child(1)).endswith(".Child(a=1, b=2, c=3)")
    assert [f.name for f in dataclasses.fields(Child)] == ["a", "b", "c"]


@pytest.mark.parametrize(
    ("body", "error"),
    [
        ({"__annotations__": {"a": "list[int]"}, "a": []}, ValueError),  # mutable default
        ({"__annotations__": {"a": "int", "b": "int"}, "a": 1}, TypeError),  # order
        ({"__annotations__": {"a": "InitVar[int]"}}, TypeError),  # not supported
    ],
    ids=["mutable-default", "default-order", "initvar"],
)
def test_a_record_refuses_a_declaration_its_dataclass_would_not_make(
    body: dict[str, Any], error: type[Exception]
) -> None:
    with pytest.raises(error):
        record(type("Bad", (), {**body, "__module__": __name__}))


def test_a_repr_of_a_record_that_contains_itself_ends() -> None:
    @record
    class Node:
        children: list[Any] = field(default_factory=list)

    node = Node()
    node.children.append(node)
    assert repr(node).endswith(".Node(children=[...])")


def test_field_names_are_the_dataclass_fields_names() -> None:
    _, rc = _pair(frozen=True)
    assert field_names(rc) == field_names(rc(1)) == ("x", "y", "z")
    assert field_names(rc) == tuple(f.name for f in dataclasses.fields(rc))


def test_fields_left_out_of_repr_and_comparison() -> None:
    def make(decorator: Callable[..., Any], fld: Callable[..., Any]) -> type:
        @decorator(frozen=True)
        class Probe:
            a: int
            b: int = fld(default=0, repr=False, compare=False)

        return Probe

    dc, rc = make(dataclasses.dataclass, dataclasses.field), make(record, field)
    assert repr(rc(1, 2)).endswith("Probe(a=1)") and repr(dc(1, 2)).endswith("Probe(a=1)")
    assert rc(1, 2) == rc(1, 3) and hash(rc(1, 2)) == hash(rc(1, 3)) == hash(dc(1, 2))
    assert [(f.repr, f.compare) for f in dataclasses.fields(rc)] == [(True, True), (False, False)]
