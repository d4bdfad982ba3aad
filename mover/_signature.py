"""Checking a remote call's arguments against the procedure's signature and type hints.

Checks are compiled once, when a procedure is exported. What arrives over msgpack is plain data,
so the checks are structural: ``int`` (not bool), ``float`` (an int is accepted and converted),
``bool``, ``str``, ``bytes``, ``None``, ``list[T]``, ``tuple[...]`` (a list is accepted),
``dict[K, V]``, unions and ``Optional``, ``Literal``, ``Any``, numpy arrays, and any other class by
``isinstance``. A hint mover cannot check is not checked.
"""

from __future__ import annotations

import inspect
import sys
import types
import typing
from collections.abc import Callable
from typing import Any

Check = Callable[[Any], Any]  # returns the (possibly converted) value or raises TypeError


def _fail(expected: str, value: Any) -> typing.NoReturn:
    raise TypeError(f"expected {expected}, got {type(value).__name__} {value!r:.60}")


def _check_int(v: Any) -> Any:
    if isinstance(v, bool) or not isinstance(v, int):
        _fail("int", v)
    return v


def _check_float(v: Any) -> Any:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        _fail("float", v)
    return float(v)


def _simple(t: type) -> Check:
    def check(v: Any) -> Any:
        if not isinstance(v, t):
            _fail(t.__name__, v)
        return v

    return check


def compile_check(hint: Any) -> Check | None:
    """A checker for one type hint, or None when anything goes."""
    if hint is Any or hint is object or hint is inspect.Parameter.empty:
        return None
    if hint is None or hint is type(None):
        return _simple(type(None))
    if hint is int:
        return _check_int
    if hint is float:
        return _check_float
    np = sys.modules.get("numpy")  # a hint naming numpy's array was written with numpy imported
    if np is not None and hint is np.ndarray:
        return _simple(np.ndarray)
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin is typing.Union or origin is types.UnionType:
        options = [compile_check(a) for a in args]
        if any(c is None for c in options):
            return None
        return _union([c for c in options if c is not None], hint)
    if origin is typing.Literal:
        allowed = args

        def check_literal(v: Any) -> Any:
            if v not in allowed:
                _fail(f"one of {allowed!r}", v)
            return v

        return check_literal
    if origin in (list, typing.Sequence, set, frozenset):
        item = compile_check(args[0]) if args else None
        return _sequence(item, "list")
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return _sequence(compile_check(args[0]), "tuple")
        return _fixed_tuple([compile_check(a) for a in args])
    if origin in (dict, typing.Mapping):
        return _mapping(*(compile_check(a) for a in args) if args else (None, None))
    if origin is not None:
        hint = origin
    if isinstance(hint, type):
        return _simple(hint)
    return None


def _union(options: list[Check], hint: Any) -> Check:
    def check(v: Any) -> Any:
        for option in options:
            try:
                return option(v)
            except TypeError:
                continue
        _fail(str(hint).replace("typing.", ""), v)

    return check


def _sequence(item: Check | None, name: str) -> Check:
    def check(v: Any) -> Any:
        if not isinstance(v, (list, tuple)):
            _fail(name, v)
        if item is None:
            return v
        out = []
        for i, x in enumerate(v):
            try:
                out.append(item(x))
            except TypeError as exc:
                raise TypeError(f"item {i}: {exc}") from None
        return out

    return check


def _fixed_tuple(items: list[Check | None]) -> Check:
    def check(v: Any) -> Any:
        if not isinstance(v, (list, tuple)) or len(v) != len(items):
            _fail(f"a sequence of {len(items)}", v)
        return [c(x) if c else x for c, x in zip(items, v, strict=True)]

    return check


def _mapping(key: Check | None, value: Check | None) -> Check:
    def check(v: Any) -> Any:
        if not isinstance(v, dict):
            _fail("dict", v)
        if key is None and value is None:
            return v
        return {(key(k) if key else k): (value(x) if value else x) for k, x in v.items()}

    return check


class Signature:
    """A procedure's signature with compiled checks for its parameters."""

    def __init__(self, fn: Callable[..., Any]) -> None:
        self.signature = inspect.signature(fn)
        try:
            hints = typing.get_type_hints(fn)
        except Exception:  # unresolved forward references: check what we can
            hints = {}
        self._hints = hints
        self.checks: dict[str, Check] = {}
        self.variadic: dict[str, inspect._ParameterKind] = {}
        for name, param in self.signature.parameters.items():
            check = compile_check(hints.get(name, param.annotation))
            if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
                self.variadic[name] = param.kind
            if check is not None:
                self.checks[name] = check
        # Prepared once: the common call (positional arguments only, to a procedure without
        # *args, **kwargs or keyword-only parameters) is checked without inspect's binding.
        params = list(self.signature.parameters.values())
        self._plain = all(p.kind is p.POSITIONAL_OR_KEYWORD for p in params)
        self._positional = [(p.name, self.checks.get(p.name)) for p in params]
        self._required = sum(1 for p in params if p.default is p.empty)
        self._index = {p.name: i for i, p in enumerate(params)}
        self._defaults = [p.default for p in params]

    def bind(self, args: list[Any], kwargs: dict[str, Any]) -> tuple[list[Any], dict[str, Any]]:
        """Checked (and converted) arguments; raise TypeError saying what is wrong."""
        if self._plain and len(args) <= len(self._positional):
            out = self._placed(args, kwargs)
            if out is not None:
                return out, {}
        bound = self.signature.bind(*args, **kwargs)
        for name, value in bound.arguments.items():
            check = self.checks.get(name)
            if check is None:
                continue
            kind = self.variadic.get(name)
            try:
                if kind is inspect.Parameter.VAR_POSITIONAL:
                    bound.arguments[name] = tuple(check(v) for v in value)
                elif kind is inspect.Parameter.VAR_KEYWORD:
                    bound.arguments[name] = {k: check(v) for k, v in value.items()}
                else:
                    bound.arguments[name] = check(value)
            except TypeError as exc:
                raise TypeError(f"argument {name!r}: {exc}") from None
        return list(bound.args), dict(bound.kwargs)

    def _placed(self, args: list[Any], kwargs: dict[str, Any]) -> list[Any] | None:
        """The checked arguments in their places (keywords too, defaults filling the gaps),
        prepared at export; None if that is not simple (then inspect binds, and says what is
        wrong)."""
        n = len(args)
        if kwargs:
            out = list(args) + self._defaults[n:]
            given = list(range(n))
            for name, value in kwargs.items():
                i = self._index.get(name)
                if i is None or i < n:
                    return None
                out[i] = value
                given.append(i)
            if any(v is inspect.Parameter.empty for v in out):
                return None
        elif n < self._required:
            return None
        else:
            out, given = list(args), list(range(n))
        for i in given:
            name, check = self._positional[i]
            if check is not None:
                try:
                    out[i] = check(out[i])
                except TypeError as exc:
                    raise TypeError(f"argument {name!r}: {exc}") from None
        return out

    def describe(self) -> str:
        """The signature as text (for listings), with its annotations resolved where they can be
        (``a: int``, not ``a: 'int'``)."""
        hints = self._hints
        params = [
            p.replace(annotation=hints.get(p.name, p.annotation))
            for p in self.signature.parameters.values()
        ]
        text = str(
            self.signature.replace(
                parameters=params,
                return_annotation=hints.get("return", self.signature.return_annotation),
            )
        )
        return text.replace("typing.", "")
