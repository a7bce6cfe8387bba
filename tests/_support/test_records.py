"""_support/records.py: record classes made without the dataclasses module
behave as dataclasses do for what the project uses (issue 26.1: start-up)."""

import copy
import dataclasses
import pickle
import subprocess
import sys

import pytest

from plcbuilder._support.records import FrozenInstanceError, dataclass, field, fields_of, replace


@dataclass(frozen=True)
class Frozen:
    x: int
    y: str = "a"
    z: tuple = field(default_factory=tuple)


@dataclass(slots=True, eq=False)
class Node:
    x: int
    y: int = 0


@dataclass
class Plain:
    a: int
    items: list = field(default_factory=list)
    b: int = field(default=0, init=False, repr=False, compare=False)

    def __post_init__(self):
        self.b = self.a * 2


@dataclass
class Child(Plain):
    c: str = "c"


def test_constructor_defaults_and_factories():
    assert Frozen(1) == Frozen(1, "a", ())
    p, q = Plain(1), Plain(1)
    assert p.items == [] and p.items is not q.items
    assert p.b == 2 and Plain(3).b == 6
    assert Child(1, [2], "d").c == "d" and Child(1).items == []
    with pytest.raises(TypeError):
        Frozen()                                             # x is required


def test_repr_equality_and_hashing_as_dataclasses():
    assert repr(Frozen(1, "b")) == "Frozen(x=1, y='b', z=())"
    assert repr(Plain(2)) == "Plain(a=2, items=[])"          # b: repr=False
    assert Plain(2) == Plain(2) and Plain(2) != Plain(3)
    a = Plain(2)
    a.b = 99                                                 # compare=False
    assert a == Plain(2)
    assert hash(Frozen(1)) == hash(Frozen(1)) and len({Frozen(1), Frozen(1)}) == 1
    with pytest.raises(TypeError):
        hash(Plain(1))                                       # eq and not frozen: unhashable
    n = Node(1)
    assert n != Node(1) and hash(n) == hash(n)               # eq=False: identity


def test_frozen_and_slots():
    f = Frozen(1)
    with pytest.raises(FrozenInstanceError):
        f.x = 2
    with pytest.raises(dataclasses.FrozenInstanceError.__mro__[1]):   # an AttributeError
        del f.x
    n = Node(1)
    n.y = 5
    assert not hasattr(n, "__dict__") and Node.__slots__ == ("x", "y")
    with pytest.raises(AttributeError):
        n.other = 1


def test_the_standard_functions_work_on_records():
    f = Frozen(1, "b")
    assert dataclasses.is_dataclass(f)
    assert [x.name for x in dataclasses.fields(f)] == ["x", "y", "z"] == list(fields_of(f))
    assert dataclasses.replace(f, x=2) == Frozen(2, "b") == replace(f, x=2)
    assert dataclasses.asdict(Plain(1, [2])) == {"a": 1, "items": [2], "b": 2}
    assert replace(Plain(1, [3]), a=4) == Plain(4, [3])


def test_copy_and_pickle():
    for obj in (Frozen(1, "b", (2,)), Plain(3, [1]), Child(2)):
        assert pickle.loads(pickle.dumps(obj)) == obj
        assert copy.deepcopy(obj) == obj
    n = pickle.loads(pickle.dumps(Node(4, 5)))
    assert (n.x, n.y) == (4, 5)


def test_making_records_does_not_load_dataclasses():
    code = ("import sys; from plcbuilder._support.records import dataclass\n"
            "@dataclass(frozen=True)\nclass A:\n    x: int\n"
            "A(1) == A(1); hash(A(1)); repr(A(1))\n"
            "print('dataclasses' in sys.modules, 'inspect' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.stdout.split() == ["False", "False"], r.stdout + r.stderr


def test_init_is_made_when_the_class_makes_its_first_instance():
    """Issue 26.1: a command loads many record classes and makes instances of
    few; an ``__init__`` is compiled only for a class that is used."""
    @dataclass(slots=True)
    class Lazy:
        x: int
        y: list = field(default_factory=list)

    class Sub(Lazy):                         # a plain subclass calling the record's __init__
        __slots__ = ("z",)

        def __init__(self, x, z):
            super().__init__(x)
            self.z = z

    made = Lazy.__dict__["__init__"]
    assert made.__code__.co_varnames[:1] == ("self",) and "x" not in made.__code__.co_varnames
    s = Sub(1, 2)                            # the first instance makes the real one
    real = Lazy.__dict__["__init__"]
    assert real is not made and real.__code__.co_varnames[:3] == ("self", "x", "y")
    assert (s.x, s.y, s.z) == (1, [], 2) and Lazy(3, [4]).y == [4]
    assert Lazy.__init__.__qualname__.endswith("Lazy.__init__")
    with pytest.raises(TypeError, match="missing 1 required positional argument: 'x'"):
        Lazy()
    with pytest.raises(TypeError, match="non-default argument 'b' follows default argument"):
        @dataclass
        class Bad:                           # the class's fields are still checked when it is made
            a: int = 0
            b: int


def test_the_written_init_templates_are_current():
    """The shapes of the package's record classes are written out in
    ``_support/record_inits.py`` (loaded from the bytecode cache, not compiled
    at every start): it must be what ``scripts/record_inits.py`` writes now."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    code = ("import sys; sys.path.insert(0, 'scripts'); import record_inits\n"
            "sys.stdout.write(record_inits.source())")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=root)
    assert r.returncode == 0, r.stderr
    written = (root / "plcbuilder" / "_support" / "record_inits.py").read_text(encoding="utf-8")
    assert written == r.stdout, "run `.venv/bin/python scripts/record_inits.py` and commit " \
                                "plcbuilder/_support/record_inits.py"


def test_a_written_template_makes_the_same_init_as_a_compiled_one():
    from plcbuilder._support import record_inits, records

    @dataclass
    class Two:
        a: int
        b: int

    assert (("p", "p"), False, False) in record_inits.SHAPES
    with pytest.raises(TypeError, match=r"Two\.__init__\(\) missing 1 required positional "
                                        r"argument: 'b'"):
        Two(1)
    t = Two(1, b=2)
    assert (t.a, t.b) == (1, 2) and Two.__init__.__code__.co_varnames == ("self", "a", "b")
    for key, init in record_inits.SHAPES.items():
        ns: dict = {}
        exec(records._init_source(*key), {}, ns)
        assert init.__code__.co_code == ns["__init__"].__code__.co_code, key
