"""Record classes: :func:`dataclasses.dataclass`'s semantics without its start-up cost.

``@dataclass`` compiles six small functions for each class it makes (``__init__``, ``__repr__``,
``__eq__``, ``__hash__``, ``__setattr__``, ``__delattr__``: ~0.5 ms a class on this machine), and
importing :mod:`dataclasses` imports :mod:`inspect` (~6 ms). ``check`` defines dozens of record
types before it reads a byte, ``wavecheck drives`` eight (issue 38). :func:`record` gives the
same classes with no code compiled per class: ``__init__`` is a template compiled once per number
of fields, its parameters renamed to the fields (so signature, keywords, defaults and error
messages are the generated one's), and the other methods are shared functions over the field
names.

What a user of a record type sees is a dataclass's: the same ``__init__`` signature (with
``<factory>`` defaults), ``repr``, ``==`` (tuples of the fields, same class only), ``hash``
(frozen), :class:`dataclasses.FrozenInstanceError` on assignment, ``__match_args__``,
``__post_init__``; :func:`dataclasses.fields`, :func:`dataclasses.replace`,
:func:`dataclasses.asdict` and :func:`dataclasses.is_dataclass` work (``__dataclass_fields__`` and
``__dataclass_params__`` are made by :mod:`dataclasses` itself the first time one is asked for).
Type checkers read :func:`record` as a dataclass (PEP 681). Supported: ``frozen``, ``eq``,
defaults, :func:`field` with ``default`` or ``default_factory`` (and ``repr``/``compare``
off), ``ClassVar`` annotations,
records inheriting records; anything else (``order``, ``slots``, ``kw_only``, ``InitVar``) is
refused at class creation.
"""

from __future__ import annotations

import builtins
import reprlib
import types
from typing import TYPE_CHECKING, Any, TypeVar, dataclass_transform, overload

if TYPE_CHECKING:
    from collections.abc import Callable

T = TypeVar("T")

__all__ = ["field", "field_names", "record", "replace"]


class _Factory:
    """The default of a field made by a factory (shown ``<factory>`` in the signature, as
    :mod:`dataclasses` shows it)."""

    __slots__ = ()

    def __repr__(self) -> str:
        return "<factory>"


_FACTORY = _Factory()
_MISSING: Any = object()
#: The names under which the fields of a record class are kept.
_FIELDS = "__record_fields__"
_DATACLASS_ATTRS = ("__dataclass_fields__", "__dataclass_params__")


class _Field:
    __slots__ = ("compare", "default", "default_factory", "repr")

    def __init__(self, default: Any, default_factory: Any, repr: bool, compare: bool) -> None:
        self.default = default
        self.default_factory = default_factory
        self.repr = repr
        self.compare = compare


def field(
    *,
    default: Any = _MISSING,
    default_factory: Callable[[], Any] = _MISSING,
    repr: bool = True,
    compare: bool = True,
) -> Any:
    """A field's default, and whether ``repr`` shows it and ``==`` / ``hash`` use it (as
    :func:`dataclasses.field`'s arguments of these names)."""
    if default is not _MISSING and default_factory is not _MISSING:
        raise ValueError("cannot specify both default and default_factory")
    return _Field(default, default_factory, repr, compare)


class _Spec:
    """A record class's fields: names, annotations, defaults (``_MISSING``: none) and
    factories (name → callable), and how the class was declared."""

    __slots__ = ("annotations", "compared", "defaults", "eq", "factories", "frozen", "names",
                 "options", "shown")  # fmt: skip

    def __init__(self, frozen: bool, eq: bool) -> None:
        self.names: tuple[str, ...] = ()
        self.shown: tuple[str, ...] = ()
        """The fields ``repr`` shows."""
        self.compared: tuple[str, ...] = ()
        """The fields ``==`` and ``hash`` use."""
        self.options: dict[str, dict[str, bool]] = {}
        """Name → ``repr=False`` / ``compare=False`` as given to :func:`field`."""
        self.annotations: dict[str, Any] = {}
        self.defaults: dict[str, Any] = {}
        self.factories: dict[str, Callable[[], Any]] = {}
        self.frozen = frozen
        self.eq = eq


_TEMPLATES: dict[int, types.CodeType] = {}


def _init_code(cls: type, names: tuple[str, ...]) -> types.CodeType:
    """``__init__(self, <names>)`` of ``cls``: ``def __init__(self, a0, …): _fill(self, (a0,
    …))``, compiled once per number of fields (~20 µs) and its parameters renamed to the fields."""
    n = len(names)
    code = _TEMPLATES.get(n)
    if code is None:
        args = "".join(f"a{k}, " for k in range(n))
        namespace: dict[str, Any] = {}
        exec(compile(f"def __init__(self, {args}):\n    _fill(self, ({args}))\n",
                     "<wavecheck.record>", "exec"), namespace)  # fmt: skip
        code = _TEMPLATES[n] = namespace["__init__"].__code__
    return code.replace(co_varnames=("self", *names), co_qualname=f"{cls.__qualname__}.__init__")


def _is_classvar(annotation: Any) -> bool:
    text = annotation if isinstance(annotation, str) else repr(annotation)
    return text.startswith(("ClassVar", "typing.ClassVar", "t.ClassVar"))


def _spec_of(cls: type, frozen: bool, eq: bool) -> _Spec:
    spec = _Spec(frozen, eq)
    for base in reversed(cls.__mro__[1:]):
        inherited: _Spec | None = base.__dict__.get(_FIELDS)
        if inherited is None:
            continue
        if inherited.frozen != frozen:
            raise TypeError(f"{cls.__qualname__}: a frozen and a mutable record cannot mix")
        spec.annotations.update(inherited.annotations)
        spec.defaults.update(inherited.defaults)
        spec.factories.update(inherited.factories)
        spec.options.update(inherited.options)
    for name, annotation in cls.__dict__.get("__annotations__", {}).items():
        if _is_classvar(annotation):
            continue
        text = annotation if isinstance(annotation, str) else repr(annotation)
        if text.startswith(("InitVar", "KW_ONLY", "dataclasses.")):
            raise TypeError(f"{cls.__qualname__}.{name}: {text} is not supported by record")
        spec.annotations[name] = annotation
        value = cls.__dict__.get(name, _MISSING)
        spec.factories.pop(name, None)
        spec.options.pop(name, None)
        if isinstance(value, _Field):
            flags = {"repr": value.repr, "compare": value.compare}
            spec.options[name] = {k: v for k, v in flags.items() if not v}
            if value.default_factory is not _MISSING:
                spec.factories[name] = value.default_factory
                value = _MISSING
                delattr(cls, name)
            else:
                value = value.default
                if value is _MISSING:
                    delattr(cls, name)
                else:
                    setattr(cls, name, value)
        if value is not _MISSING and type(value).__hash__ is None:
            raise ValueError(
                f"mutable default {type(value)} for field {name} is not allowed: use "
                "default_factory"
            )
        spec.defaults[name] = value
    spec.names = tuple(spec.annotations)
    if "self" in spec.names:
        raise TypeError(f"{cls.__qualname__}: a record field cannot be named 'self'")
    spec.shown = tuple(n for n in spec.names if spec.options.get(n, {}).get("repr", True))
    spec.compared = tuple(n for n in spec.names if spec.options.get(n, {}).get("compare", True))
    seen_default = False
    for name in spec.names:
        has_default = spec.defaults[name] is not _MISSING or name in spec.factories
        if seen_default and not has_default:
            raise TypeError(f"non-default argument {name!r} follows default argument")
        seen_default = seen_default or has_default
    return spec


def _make_init(cls: type, spec: _Spec) -> Callable[..., None]:
    names = spec.names
    factories = spec.factories
    post_init = getattr(cls, "__post_init__", None)
    put = object.__setattr__ if spec.frozen else builtins.setattr

    def fill(self: Any, values: tuple[Any, ...]) -> None:
        for name, value in zip(names, values):  # noqa: B905 - as many as the parameters
            put(self, name, value)
        if post_init is not None:
            self.__post_init__()

    def fill_factories(self: Any, values: tuple[Any, ...]) -> None:
        for name, value in zip(names, values):  # noqa: B905 - as many as the parameters
            put(self, name, factories[name]() if value is _FACTORY else value)
        if post_init is not None:
            self.__post_init__()

    scope = {
        "_fill": fill_factories if factories else fill,
        "__name__": cls.__module__,
        "__builtins__": builtins,
    }
    defaults = tuple(
        _FACTORY if n in spec.factories else spec.defaults[n]
        for n in names
        if n in spec.factories or spec.defaults[n] is not _MISSING
    )
    init = types.FunctionType(_init_code(cls, names), scope, "__init__", defaults or None)
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__annotations__ = {**spec.annotations, "return": None}
    return init


def _values(self: Any) -> tuple[Any, ...]:
    return tuple([getattr(self, n) for n in type(self).__record_fields__.compared])


@reprlib.recursive_repr()
def _repr(self: Any) -> str:
    spec: _Spec = type(self).__record_fields__
    inner = ", ".join([f"{n}={getattr(self, n)!r}" for n in spec.shown])
    return f"{type(self).__qualname__}({inner})"


def _eq(self: Any, other: Any) -> Any:
    if other.__class__ is self.__class__:
        return _values(self) == _values(other)
    return NotImplemented


def _hash(self: Any) -> int:
    return hash(_values(self))


def _frozen_methods(cls: Any, names: tuple[str, ...]) -> tuple[Any, Any]:
    def __setattr__(self: Any, name: str, value: Any) -> None:
        if type(self) is cls or name in names:
            from dataclasses import FrozenInstanceError

            raise FrozenInstanceError(f"cannot assign to field {name!r}")
        super(cls, self).__setattr__(name, value)

    def __delattr__(self: Any, name: str) -> None:
        if type(self) is cls or name in names:
            from dataclasses import FrozenInstanceError

            raise FrozenInstanceError(f"cannot delete field {name!r}")
        super(cls, self).__delattr__(name)

    __setattr__.__qualname__ = f"{cls.__qualname__}.__setattr__"
    __delattr__.__qualname__ = f"{cls.__qualname__}.__delattr__"
    return __setattr__, __delattr__


class _AsDataclass:
    """``__dataclass_fields__`` / ``__dataclass_params__`` of a record class, made by
    :func:`dataclasses.make_dataclass` from its fields the first time one is asked for (the
    introspection of :mod:`dataclasses`: ``fields``, ``replace``, ``asdict``, ``is_dataclass``
    …). The fields come from a twin made without methods (no code compiled); the parameters,
    asked for rarely, from one made as the record was declared."""

    def __init__(self, attr: str) -> None:
        self.attr = attr

    def __get__(self, obj: Any, owner: Any) -> Any:
        import dataclasses

        spec: _Spec = owner.__record_fields__
        specs: list[tuple[str, Any, Any]] = []
        for name in spec.names:
            given: dict[str, Any] = dict(spec.options.get(name, {}))
            if name in spec.factories:
                given["default_factory"] = spec.factories[name]
            elif spec.defaults[name] is not _MISSING:
                given["default"] = spec.defaults[name]
            specs.append((name, spec.annotations[name], dataclasses.field(**given)))
        if self.attr == "__dataclass_fields__":
            flags = {"init": False, "repr": False, "eq": False}
        else:
            flags = {"eq": spec.eq, "frozen": spec.frozen}
        twin = dataclasses.make_dataclass(owner.__name__, specs, **flags)  # type: ignore[arg-type]
        type.__setattr__(owner, self.attr, twin.__dict__[self.attr])
        return twin.__dict__[self.attr]


def _build(cls: type, frozen: bool, eq: bool) -> type:
    spec = _spec_of(cls, frozen, eq)
    own = cls.__dict__
    setattr(cls, _FIELDS, spec)
    for attr in _DATACLASS_ATTRS:
        setattr(cls, attr, _AsDataclass(attr))
    if "__init__" not in own:
        cls.__init__ = _make_init(cls, spec)  # type: ignore[misc]
    if "__repr__" not in own:
        cls.__repr__ = _repr  # type: ignore[assignment]
    if eq and "__eq__" not in own:
        cls.__eq__ = _eq  # type: ignore[assignment]
    if "__hash__" not in own or (own["__hash__"] is None and "__eq__" in own):
        if eq and frozen:
            cls.__hash__ = _hash  # type: ignore[assignment]
        elif eq:
            cls.__hash__ = None  # type: ignore[assignment]
    if frozen:
        if "__setattr__" in own or "__delattr__" in own:
            raise TypeError(f"cannot overwrite __setattr__/__delattr__ of {cls.__qualname__}")
        cls.__setattr__, cls.__delattr__ = _frozen_methods(cls, spec.names)  # type: ignore[method-assign]
    if "__match_args__" not in own:
        cls.__match_args__ = spec.names  # type: ignore[attr-defined,misc]
    return cls


@overload
def record(cls: type[T], /) -> type[T]: ...
@overload
def record(*, frozen: bool = False, eq: bool = True) -> Callable[[type[T]], type[T]]: ...


@dataclass_transform(field_specifiers=(field,))
def record(cls: Any = None, /, *, frozen: bool = False, eq: bool = True) -> Any:
    """Make ``cls`` a record: ``@record`` is ``@dataclass``, ``@record(frozen=True)`` is
    ``@dataclass(frozen=True)`` (see the module's docstring for what is supported)."""

    def wrap(cls: type) -> type:
        return _build(cls, frozen, eq)

    return wrap if cls is None else wrap(cls)


def replace(obj: T, /, **changes: Any) -> T:
    """A copy of ``obj`` (a record or a dataclass) with ``changes``, as
    :func:`dataclasses.replace` (without making a record's ``__dataclass_fields__``)."""
    spec: _Spec | None = getattr(type(obj), _FIELDS, None)
    if spec is None:
        import dataclasses

        return dataclasses.replace(obj, **changes)  # type: ignore[type-var]
    for name in spec.names:
        if name not in changes:
            changes[name] = getattr(obj, name)
    return type(obj)(**changes)


def field_names(class_or_record: Any) -> tuple[str, ...]:
    """The field names of a record class or record, in order (``dataclasses.fields``' names,
    without making a record's ``__dataclass_fields__``)."""
    spec: _Spec = class_or_record.__record_fields__
    return spec.names
