"""A bounded, per-process memo of results by key, least recently used dropped first.

The references (:mod:`runtime.sim.reference`), the grip along a path and the saturation
verdict (:mod:`runtime.stability.saturation`) and the measured switching gain
(:mod:`runtime.stability.analysis`) are asked for again with the same arguments, once per
controller, formulation and delay, at seconds each; each keeps its results here. The caller
builds the key (:func:`key_of`) from everything the computation reads, and copies what it
hands out where that is mutable (NumPy arrays a caller may write into).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable, Mapping
from typing import Generic, TypeVar

from runtime.bindings.generated import RobotCode

T = TypeVar("T")


def key_of(code: RobotCode, params: Mapping[str, float], *rest: Hashable
           ) -> tuple[Hashable, ...]:
    """A memo key: the robot's generated code (its folder, resolved, and prefix), the
    parameters by name as floats, then ``rest`` (whatever else the computation reads)."""
    return (str(code.folder.resolve()), code.prefix,
            tuple(sorted((k, float(v)) for k, v in params.items())), *rest)


class Memo(Generic[T]):
    """At most ``size`` results, by key."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._items: OrderedDict[Hashable, T] = OrderedDict()

    def get(self, key: Hashable, compute: Callable[[], T]) -> T:
        """The result stored under ``key``, or ``compute()``'s, stored."""
        if key in self._items:
            self._items.move_to_end(key)
            return self._items[key]
        value = compute()
        self._items[key] = value
        if len(self._items) > self.size:
            self._items.popitem(last=False)
        return value

    def __len__(self) -> int:
        return len(self._items)

    def clear(self) -> None:
        self._items.clear()
