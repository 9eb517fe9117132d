"""Objects a ``with`` block closes on leaving it: the one ``__enter__``/``__exit__`` pair that
calls ``close()``, for every class whose context is just "release what it holds"."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from types import TracebackType
    from typing import Self


class Closing:
    """A context manager whose exit is :meth:`close` (which subclasses define)."""

    __slots__ = ()

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
