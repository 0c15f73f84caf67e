"""Context-manager plumbing shared by the devices (cameras, projectors, the preview window).

``with device:`` opens it and closes it again, whatever happens inside; :meth:`Device.open` returns the
device (so ``Device(...).open()`` chains) and both do nothing unless a device has something to open or
release.
"""

from __future__ import annotations


class Device:
    """Base of procam's devices: ``open()``, ``close()`` and the context manager over them."""

    def __enter__(self):
        self.open()
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def open(self):
        return self

    def close(self) -> None:
        pass
