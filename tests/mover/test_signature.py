"""Unit tests of argument checking against signatures and type hints."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
import pytest

from mover._signature import Signature


def f(
    a: int,
    b: float,
    c: str | None = None,
    d: list[int] | None = None,
    e: tuple[float, float] = (0.0, 0.0),
    m: dict[str, bool] | None = None,
    mode: Literal["fast", "slow"] = "fast",
    arr: np.ndarray | None = None,
    anything: Any = None,
) -> None: ...


def bind(*args: Any, **kwargs: Any) -> tuple[list[Any], dict[str, Any]]:
    return Signature(f).bind(list(args), kwargs)


def test_good_arguments_pass_and_ints_become_floats() -> None:
    args, _ = bind(1, 2, "x", [1, 2], [1, 2], {"k": True}, "slow", np.zeros(2), object())
    assert args[1] == 2.0 and isinstance(args[1], float)
    assert args[4] == [1.0, 2.0]


@pytest.mark.parametrize(
    ("args", "kwargs", "message"),
    [
        ((True, 1.0), {}, "argument 'a': expected int, got bool"),
        (("1", 1.0), {}, "argument 'a': expected int, got str"),
        ((1, "x"), {}, "argument 'b': expected float"),
        ((1, 1.0), {"d": [1, "2"]}, "argument 'd'"),
        ((1, 1.0), {"e": [1.0]}, "argument 'e': expected a sequence of 2"),
        ((1, 1.0), {"m": {"k": 1}}, "argument 'm'"),
        ((1, 1.0), {"mode": "medium"}, "argument 'mode': expected one of"),
        ((1, 1.0), {"arr": [1, 2]}, "argument 'arr'"),
        ((1,), {}, "missing a required argument: 'b'"),
        ((1, 1.0), {"z": 1}, "unexpected keyword argument 'z'"),
    ],
)
def test_bad_arguments_are_named(
    args: tuple[Any, ...], kwargs: dict[str, Any], message: str
) -> None:
    with pytest.raises(TypeError, match=message):
        bind(*args, **kwargs)


def test_variadic() -> None:
    def g(*xs: int, **kw: float) -> None: ...

    sig = Signature(g)
    assert sig.bind([1, 2], {"a": 1}) == ([1, 2], {"a": 1.0})
    with pytest.raises(TypeError, match="argument 'xs'"):
        sig.bind([1, "2"], {})


def test_the_prepared_path_checks_as_the_full_binding_does() -> None:
    def add(x: int, y: float = 1.0) -> float:
        return x + y

    sig = Signature(add)
    assert sig.bind([1, 2], {}) == ([1, 2.0], {})  # positional only: the prepared path
    assert sig.bind([1], {"y": 2}) == ([1, 2.0], {})  # with keywords: inspect's binding
    for args in (["1", 2], ["1"]):
        with pytest.raises(TypeError, match="argument 'x': expected int") as fast:
            sig.bind(args, {})
        with pytest.raises(TypeError) as slow:
            sig.bind([], {"x": args[0]})
        assert str(fast.value) == str(slow.value)
    with pytest.raises(TypeError, match="missing a required argument"):
        sig.bind([], {})
    with pytest.raises(TypeError, match="too many positional"):
        sig.bind([1, 2, 3], {})


def test_keywords_are_placed_as_prepared_at_export() -> None:
    """Keyword arguments go to their places without inspect's binding (defaults fill the
    gaps, unchecked, as inspect leaves them); what is not simple still gets inspect's words."""

    def move(x: float, y: float = 0.0, speed: int | None = None) -> None: ...

    sig = Signature(move)
    assert sig.bind([1], {"speed": 3}) == ([1.0, 0.0, 3], {})
    assert sig.bind([], {"y": 2, "x": 1}) == ([1.0, 2.0, None], {})
    with pytest.raises(TypeError, match="argument 'speed': expected"):
        sig.bind([1], {"speed": "fast"})
    with pytest.raises(TypeError, match="multiple values for argument 'x'"):
        sig.bind([1], {"x": 2})
    with pytest.raises(TypeError, match="unexpected keyword argument 'z'"):
        sig.bind([1], {"z": 2})
    with pytest.raises(TypeError, match="missing a required argument: 'x'"):
        sig.bind([], {"y": 2})
