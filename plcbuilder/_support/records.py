"""Record classes made quickly: ``@dataclass`` for the modules every command
loads (the compiler, diagnostics, the facade).

The standard ``dataclasses`` costs a command's start-up more than the whole
compile of a small file: importing it loads ``inspect`` (and with it ``ast``,
``dis``, ``tokenize``), and each class gets three functions written and
compiled from source (``__init__``, ``__repr__``, ``__eq__``). Here a class
gets only its ``__init__``, and that compiled once per shape of fields (how
many, which have defaults), renamed for the class, and made when the class
makes its first instance (a command loads many record classes and uses few);
``__repr__``, ``__eq__``
and ``__hash__`` are shared functions reading the class's field names. The result behaves as the
standard one for what this project uses (the same constructor, repr, equality,
hashing, ``frozen``, ``slots``, ``eq=False``, ``field(default_factory=…,
init=, repr=, compare=)`` and ``__post_init__``), and the standard module's
own functions (``dataclasses.replace``, ``fields``, ``asdict``,
``is_dataclass``) work on it: ``__dataclass_fields__`` is built, importing
``dataclasses``, the first time one of them asks. :func:`replace` here does
the same without that import.
"""

from __future__ import annotations

import builtins
from types import FunctionType

__all__ = ["dataclass", "field", "replace", "fields_of", "asdict", "FrozenInstanceError"]


class _Missing:
    __slots__ = ()

    def __repr__(self):
        return "MISSING"


MISSING = _Missing()


class FrozenInstanceError(AttributeError):
    """Assigning to a field of a frozen record (as ``dataclasses.FrozenInstanceError``)."""


class Field:
    """What ``field(...)`` says about one field."""
    __slots__ = ("default", "default_factory", "init", "repr", "compare")

    def __init__(self, default=MISSING, default_factory=MISSING, init=True, repr=True,
                 compare=True):
        self.default, self.default_factory = default, default_factory
        self.init, self.repr, self.compare = init, repr, compare


def field(*, default=MISSING, default_factory=MISSING, init: bool = True, repr: bool = True,
          compare: bool = True) -> Field:
    return Field(default, default_factory, init, repr, compare)


def _is_classvar(annotation) -> bool:
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__", "")
    return text.startswith(("ClassVar", "typing.ClassVar"))


def _repr(self) -> str:
    parts = ", ".join(f"{n}={getattr(self, n)!r}" for n in type(self).__record_repr__)
    return f"{type(self).__qualname__}({parts})"


def _eq(self, other):
    if other.__class__ is self.__class__:
        names = self.__class__.__record_compare__
        return tuple(getattr(self, n) for n in names) == tuple(getattr(other, n) for n in names)
    return NotImplemented


def _hash(self) -> int:
    return hash(tuple(getattr(self, n) for n in type(self).__record_compare__))


def _frozen_setattr(self, name, value):
    raise FrozenInstanceError(f"cannot assign to field '{name}'")


def _frozen_delattr(self, name):
    raise FrozenInstanceError(f"cannot delete field '{name}'")


class _DataclassFields:
    """``__dataclass_fields__``, made (with the standard module) on first use."""

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, cls):
        made = cls.__dict__.get("__record_std_fields__")
        if made is None:
            import dataclasses
            made = {}
            for name, spec in cls.__record_fields__.items():
                std = dataclasses.MISSING
                f = dataclasses.field(
                    default=std if spec.default is MISSING else spec.default,
                    default_factory=std if spec.default_factory is MISSING else spec.default_factory,
                    init=spec.init, repr=spec.repr, compare=spec.compare)
                f.name = name
                f.type = cls.__record_types__.get(name)
                f._field_type = dataclasses._FIELD     # noqa: SLF001 - what dataclasses reads
                made[name] = f
            type.__setattr__(cls, "__record_std_fields__", made)
        return made


#: compiled __init__ code by the shape of a class's fields (see _init_code)
_TEMPLATES: dict = {}
#: the shapes of the package's own record classes made so far (what
#: ``scripts/record_inits.py`` writes out)
_PACKAGE_SHAPES: set = set()
#: the written-out templates (record_inits.SHAPES), loaded when first needed
_written = None


def _init_code(kinds: tuple, frozen: bool, post_init: bool):
    """The code of an ``__init__`` for fields of these kinds ('p' a parameter,
    'f' a parameter whose default is a factory's, 'd'/'F' not a parameter, set
    to a default/a factory's value, '-' not set), with the fields named a0,
    a1, …: made once per shape and renamed for each class. The shapes of the
    package's record classes are written out in :mod:`record_inits` (loaded
    from its bytecode cache: compiling is most of what making a record costs);
    another shape is compiled here."""
    global _written
    key = (kinds, frozen, post_init)
    code = _TEMPLATES.get(key)
    if code is None:
        if _written is None:
            from . import record_inits
            _written = record_inits.SHAPES
        init = _written.get(key)
        if init is None:
            ns: dict = {}
            exec(compile(_init_source(*key), "<record>", "exec"), {}, ns)  # noqa: S102 - our own
            init = ns["__init__"]
        code = _TEMPLATES[key] = init.__code__.replace(co_name="__init__")
    return code


def _init_source(kinds: tuple, frozen: bool, post_init: bool, name: str = "__init__") -> str:
    """The source of the ``__init__`` of a shape (see :func:`_init_code`)."""
    params, body = [], []
    for i, k in enumerate(kinds):
        if k == "-":
            continue
        if k in "pf":
            params.append(f"a{i}")
        if k == "f":
            body.append(f"    if a{i} is MISSING: a{i} = _f{i}()")
        value = {"p": f"a{i}", "f": f"a{i}", "d": f"_d{i}", "F": f"_f{i}()"}[k]
        body.append(f"    __record_set(self, 'a{i}', {value})" if frozen
                    else f"    self.a{i} = {value}")
    if post_init:
        body.append("    self.__post_init__()")
    return f"def {name}(self{''.join(', ' + p for p in params)}):\n" \
        + ("\n".join(body) or "    pass") + "\n"


def inits_source(shapes) -> str:
    """The text of ``record_inits.py``: an ``__init__`` template for each shape."""
    shapes = sorted(shapes)
    out = ['"""The ``__init__`` templates of the shapes of the package\'s record classes',
           "(:mod:`plcbuilder._support.records`), loaded from this module's bytecode",
           "cache instead of compiled at every start. Written by",
           "``scripts/record_inits.py``; tests/_support/test_records.py",
           'checks it is current. The names each template uses are the globals the',
           'records module gives the class\'s ``__init__``."""',
           "# (generated: do not edit)", ""]
    for n, key in enumerate(shapes):
        out += ["", _init_source(*key, name=f"_init{n}")]
    out += ["", "SHAPES = {"]
    out += [f"    {key!r}: _init{n}," for n, key in enumerate(shapes)]
    out += ["}", ""]
    return "\n".join(out)


def made_shapes() -> set:
    """The shapes of the package's record classes made so far in this process
    (``scripts/record_inits.py`` imports every module, then writes these out)."""
    return set(_PACKAGE_SHAPES)


def dataclass(cls=None, /, *, frozen: bool = False, slots: bool = False, eq: bool = True,
              repr: bool = True):
    """A record class: ``@dataclass``, ``@dataclass(frozen=True)``, ``slots=True``, ``eq=False``."""
    def wrap(c):
        return _make(c, frozen, slots, eq, repr)
    return wrap if cls is None else wrap(cls)


def _make(cls, frozen: bool, slots: bool, eq: bool, want_repr: bool):
    specs: dict[str, Field] = {}
    types: dict = {}
    for base in reversed(cls.__mro__[1:]):
        specs.update(base.__dict__.get("__record_fields__", {}))
        types.update(base.__dict__.get("__record_types__", {}))
    own = cls.__dict__.get("__annotations__", {})
    for name, annotation in own.items():
        if _is_classvar(annotation):
            continue
        value = cls.__dict__.get(name, MISSING)
        specs[name] = value if isinstance(value, Field) else Field(default=value)
        types[name] = annotation
    names = list(specs)

    # __init__: the one function made for the class
    kinds, defaults, g = [], [], {"MISSING": MISSING, "__record_set": object.__setattr__,
                                  "__builtins__": builtins}
    seen_default = False
    for i, name in enumerate(names):
        f = specs[name]
        if f.init:
            if f.default is not MISSING:
                kinds.append("p")
                defaults.append(f.default)
                seen_default = True
            elif f.default_factory is not MISSING:
                kinds.append("f")
                defaults.append(MISSING)
                g[f"_f{i}"] = f.default_factory
                seen_default = True
            else:
                if seen_default:
                    raise TypeError(f"non-default argument '{name}' follows default argument")
                kinds.append("p")
        elif f.default_factory is not MISSING:
            kinds.append("F")
            g[f"_f{i}"] = f.default_factory
        elif f.default is not MISSING:
            kinds.append("d")
            g[f"_d{i}"] = f.default
        else:
            kinds.append("-")
    shape = (tuple(kinds), frozen, hasattr(cls, "__post_init__"), tuple(names), g,
             tuple(defaults) or None)
    if cls.__module__.startswith("plcbuilder."):
        _PACKAGE_SHAPES.add(shape[:3])

    extra = {"__record_fields__": specs, "__record_types__": types,
             "__record_repr__": tuple(n for n in names if specs[n].repr),
             "__record_compare__": tuple(n for n in names if specs[n].compare),
             "__dataclass_fields__": _DataclassFields(),
             "__match_args__": tuple(n for n in names if specs[n].init)}
    if want_repr and "__repr__" not in cls.__dict__:
        extra["__repr__"] = _repr
    if eq and "__eq__" not in cls.__dict__:
        extra["__eq__"] = _eq
    if "__hash__" not in cls.__dict__ or (eq and cls.__dict__.get("__hash__") is None):
        if eq and frozen:
            extra["__hash__"] = _hash
        elif eq:
            extra["__hash__"] = None
    if frozen:
        extra["__setattr__"] = _frozen_setattr
        extra["__delattr__"] = _frozen_delattr
    if slots:                # a new class with __slots__ (as dataclasses does)
        if frozen:
            raise TypeError("frozen records with slots are not supported")
        ns = dict(cls.__dict__)
        inherited = {s for b in cls.__mro__[1:] for s in b.__dict__.get("__slots__", ())}
        ns["__slots__"] = tuple(n for n in names if n not in inherited)
        for n in names:
            ns.pop(n, None)                          # defaults live in __init__, not the class
        ns.pop("__dict__", None)
        ns.pop("__weakref__", None)
        ns.update(extra)
        new = type(cls)(cls.__name__, cls.__bases__, ns)
        new.__qualname__ = cls.__qualname__
        new.__init__ = _deferred_init(new, shape)
        return new
    for n in names:                                  # as dataclasses: a plain default stays
        if isinstance(cls.__dict__.get(n), Field):
            if specs[n].default is MISSING:
                delattr(cls, n)
            else:
                setattr(cls, n, specs[n].default)
    for k, v in extra.items():
        setattr(cls, k, v)
    cls.__init__ = _deferred_init(cls, shape)
    return cls


def _deferred_init(cls, shape):
    """The class's ``__init__`` until it is first called: it then makes the
    real one (:func:`_init_function`), puts it in the class and calls it. A
    command loads many record classes and makes instances of few: the others'
    ``__init__`` is never compiled."""
    def __init__(self, *args, **kwargs):
        init = _init_function(cls, *shape)
        cls.__init__ = init
        init(self, *args, **kwargs)
    __init__.__qualname__ = f"{cls.__qualname__}.__init__"
    __init__.__module__ = cls.__module__
    return __init__


def _init_function(cls, kinds: tuple, frozen: bool, post_init: bool, names: tuple, g: dict,
                   defaults):
    """The ``__init__`` of a record class: the code of its shape of fields
    (:func:`_init_code`) with the fields' names."""
    code = _init_code(kinds, frozen, post_init)
    rename = {f"a{i}": name for i, name in enumerate(names)}
    code = code.replace(
        co_varnames=tuple(rename.get(v, v) for v in code.co_varnames),
        co_names=tuple(rename.get(v, v) for v in code.co_names),
        co_consts=tuple(rename.get(c, c) if type(c) is str else c for c in code.co_consts),
        co_qualname=f"{cls.__qualname__}.__init__")
    init = FunctionType(code, g, "__init__", defaults)
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__module__ = cls.__module__
    return init


def fields_of(obj) -> tuple[str, ...]:
    """The field names of a record (class or instance), in order."""
    cls = obj if isinstance(obj, type) else type(obj)
    return tuple(cls.__record_fields__)


def replace(obj, **changes):
    """A copy of a record with some fields changed (``dataclasses.replace``)."""
    cls = type(obj)
    specs = cls.__dict__.get("__record_fields__")
    if specs is None:
        import dataclasses
        return dataclasses.replace(obj, **changes)
    for name, f in specs.items():
        if f.init and name not in changes:
            changes[name] = getattr(obj, name)
    return cls(**changes)


_PLAIN = frozenset((int, str, float, bool, bytes, type(None)))


def asdict(obj):
    """A record as a dict, records, lists, tuples and dicts in it converted
    the same way, and copied (``dataclasses.asdict``)."""
    cls = type(obj)
    if cls in _PLAIN:
        return obj
    if hasattr(cls, "__record_fields__"):
        return {n: asdict(getattr(obj, n)) for n in cls.__record_fields__}
    if isinstance(obj, tuple) and hasattr(obj, "_fields"):           # a namedtuple
        return cls(*[asdict(v) for v in obj])
    if isinstance(obj, (list, tuple)):
        return cls(asdict(v) for v in obj)
    if isinstance(obj, dict):
        return cls((asdict(k), asdict(v)) for k, v in obj.items())
    if hasattr(cls, "__dataclass_fields__"):
        import dataclasses
        return dataclasses.asdict(obj)
    import copy
    return copy.deepcopy(obj)
