"""Read pose folders ahead: the images of the next pose are read in background threads while this one is
processed, so decoding, corner detection and the checks of a multi-pose run overlap the reading of the PNGs
(which is most of a run's time).

:class:`Prefetcher` reads the folders' images in order, at most ``ahead`` poses ahead of the one being
processed (memory stays bounded: the pose in use plus ``ahead`` being read; a stack the caller no longer refers
to is filled again with a later pose instead of a new one), and hands them over through
:meth:`Prefetcher.read`, a drop-in for :func:`procam.io.images.read_images` that
:func:`procam.capture.load_capture` takes as its ``reader``. Anything unusual (a file list other than the
folder's, images of different sizes or bit depths, a file that cannot be read) is read again by
:func:`procam.io.images.read_images` itself, so errors are the same, word for word.

Given a :class:`procam.io.child_reader.ChildReader` (``child=``: the command line forks one as it starts), the
images are read by that child process into shared memory instead of by threads here: the same stacks, read
without taking this process's interpreter lock from the work beside them.

>>> from procam import stream, capture
>>> with stream.Prefetcher(["pose1", "pose2"]) as pf:            # doctest: +SKIP
...     caps = [capture.load_capture(f, reader=pf.read) for f in ["pose1", "pose2"]]
"""

from __future__ import annotations

import os
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from . import capture
from .io import files as _files
from .io import images as _images


class _Pose:
    """One folder being read: its files, the stack filled in by the reader threads, the first failure."""

    def __init__(self, files, spare=None):
        self.files = tuple(files)
        self.stack = None
        self.spare = spare  # (shape, dtype) -> a stack handed out before that no one refers to any more, or None
        self.failed = False
        self.left = len(self.files)
        self.done = threading.Event()
        self.lock = threading.Lock()
        self.ticket = None  # read by the child process: its ticket (ChildReader.wait)
        if not self.files:
            self.done.set()

    def _new_stack(self, frame_shape, dtype):
        """The stack for frames of ``frame_shape`` and ``dtype``: a spare one, else a new one (the lock held)."""
        shape, dtype = (len(self.files),) + tuple(frame_shape), np.dtype(dtype)
        self.stack = self.spare(shape, dtype) if self.spare else None
        if self.stack is None:
            self.stack = np.empty(shape, dtype)

    def slot(self, i: int, path) -> np.ndarray | None:
        """Frame ``i`` of the stack, for the reader to decode the image into (no copy), or None: the stack is made
        (or taken from the spares) from the first image's PNG header; None before it is made from any other
        image, or after a failure."""
        with self.lock:
            if self.stack is None and not self.failed:
                head = _images.png_header(path)  # (height, width, bytes per sample)
                if head is not None:
                    self._new_stack(head[:2], np.uint8 if head[2] == 1 else np.uint16)
            return None if self.stack is None or self.failed else self.stack[i]

    def put(self, i: int, img: np.ndarray | None, slot: np.ndarray | None = None):
        with self.lock:
            if img is None:
                self.failed = True
            elif img is slot:  # decoded into the stack
                pass
            elif not self.failed:
                if self.stack is None:
                    self._new_stack(img.shape, img.dtype)
                if img.shape != self.stack.shape[1:] or img.dtype != self.stack.dtype:
                    self.failed = True  # read_images names the file that differs
                else:
                    self.stack[i] = img
            self.left -= 1
            if self.left == 0:
                self.done.set()


class Prefetcher:
    """Reads the images of ``folders`` in order, ``ahead`` poses ahead of :meth:`read`.

    Parameters
    ----------
    folders : pose folders, in the order they will be read.
    threads : reader threads (OpenCV's PNG decoder releases the GIL); default ``min(2, cpu_count)``.
    ahead : poses read ahead of the one handed out last (1: the next pose is read while this one is processed;
        the first pose is read from the start).
    gray : as :func:`procam.io.images.read_images`.
    child : a :class:`procam.io.child_reader.ChildReader` that reads the images instead of threads (its own
        threads), or None; the Prefetcher closes it.

    Use as a context manager (the threads, or the child, stop on exit); :meth:`read` is the reader for
    :func:`procam.capture.load_capture`.
    """

    def __init__(self, folders, threads: int | None = None, ahead: int = 1, gray: bool = True, child=None):
        self.folders = [Path(f) for f in folders]
        self.gray = gray
        self.ahead = max(1, int(ahead))
        n = threads if threads is not None else min(2, os.cpu_count() or 1)
        self.child = child
        self._shared: dict[int, int] = {}  # id() of a stack in shared memory -> the child's buffer id
        self._pool = None if child is not None else ThreadPoolExecutor(max(1, n), thread_name_prefix="procam-read")
        self._poses: dict[tuple, _Pose] = {}
        self._next = 0          # next folder to start reading
        self._handed = 0        # poses handed out by read()
        self._closed = False
        self._lock = threading.RLock()  # reentrant: a pose given to the child takes its spare stack under it
        self._handed_stacks = []
        self._fill()

    # -- scheduling ----------------------------------------------------------------------------
    def _fill(self):
        """Start reading folders until ``ahead`` poses are ahead of those handed out."""
        with self._lock:
            while not self._closed and self._next < len(self.folders) and self._next < self._handed + self.ahead:
                folder = self.folders[self._next]
                self._next += 1
                try:  # the files load_capture will ask for: the sequence, not procam's outputs beside it
                    files, _ = capture.sequence_files(folder, _files.list_images(folder))
                except Exception:  # load_capture reports it
                    continue
                pose = _Pose(files, self._spare)
                self._poses[tuple(str(f) for f in files)] = pose
                if self.child is not None:
                    self._to_child(pose)
                    continue
                for i, f in enumerate(pose.files):
                    self._pool.submit(self._load, pose, i, f)

    def _to_child(self, pose: _Pose):
        """Have the child process read ``pose`` into a stack in shared memory (a spare one, else a new one), its
        frame size and type from the first file's PNG header; without a header (another format, a file that cannot
        be read) it is not read ahead, and :meth:`read` reads it (the lock held)."""
        head = _images.png_header(pose.files[0]) if pose.files else None
        if head is None:
            pose.failed = True
            pose.done.set()
            return
        shape, dtype = (len(pose.files),) + tuple(head[:2]), np.dtype(np.uint8 if head[2] == 1 else np.uint16)
        stack = pose.spare(shape, dtype)
        buffer = self._shared.get(id(stack)) if stack is not None else None
        if buffer is None:
            made = self.child.new_buffer(int(np.prod(shape)) * dtype.itemsize)
            if made is None:
                pose.failed = True
                pose.done.set()
                return
            mem, buffer = made
            stack = np.frombuffer(mem, dtype, int(np.prod(shape))).reshape(shape)
        pose.stack = stack
        self._shared[id(stack)] = buffer
        pose.ticket = self.child.submit(pose.files, buffer, shape, dtype.name, self.gray)
        if pose.ticket is None:  # the child is gone, or the command too long: read() reads the pose
            pose.failed = True
            pose.done.set()

    def _spare(self, shape, dtype):
        """A stack handed out before that nothing refers to any more, to fill with the next pose: its pages are
        mapped already, where a new one costs the kernel a fresh zeroed page at every first write (about a tenth
        of a 5-pose calibrate's system time).  Told by CPython's reference count: only this list's and the call's
        (a Capture, a view of the stack, a caller's name each add one, and any of them keeps it from being
        reused); None elsewhere."""
        count = getattr(sys, "getrefcount", None)
        if count is None:
            return None
        with self._lock:
            kept = self._handed_stacks
            for k in range(len(kept)):
                if kept[k].shape == shape and kept[k].dtype == dtype and count(kept[k]) == 2:
                    return kept.pop(k)
        return None

    def _load(self, pose: _Pose, i: int, path):
        if self._closed or pose.failed:
            pose.put(i, None)
            return
        slot = img = None
        try:
            slot = pose.slot(i, path) if self.gray else None
            img = _images.read_image(path, self.gray, slot)
        except Exception:  # no memory for a stack a header asks for, a file that cannot be read: read() reads
            pass           # the pose again the ordinary way, which says what is wrong
        try:
            pose.put(i, img, slot)
        except Exception:  # no memory for the stack: the frame still counts, or read() would wait for it forever
            pose.put(i, None)

    # -- the reader ----------------------------------------------------------------------------
    def read(self, files) -> np.ndarray:
        """The stack of ``files`` (K, H, W): read ahead when they are a folder's images, else read now.

        Same result and same errors as :func:`procam.io.images.read_images`.
        """
        key = tuple(str(Path(f)) for f in files)
        with self._lock:
            pose = self._poses.pop(key, None)
            self._handed += 1
        self._fill()
        if pose is not None:
            if pose.ticket is not None:
                pose.failed = not self.child.wait(pose.ticket)
                pose.done.set()
            pose.done.wait()
            if not pose.failed and pose.stack is not None:
                with self._lock:  # kept for reuse: the last few only (others are the caller's to free)
                    kept = [*self._handed_stacks[-self.ahead:], pose.stack]
                    for old in self._handed_stacks[:-self.ahead]:
                        self._unshare(old)
                    self._handed_stacks = kept
                return pose.stack
            if pose.stack is not None:
                with self._lock:
                    self._unshare(pose.stack)
        return _images.read_images(files, self.gray)

    def _unshare(self, stack):
        """The child process forgets ``stack``'s shared buffer (never filled again: the caller keeps it, or frees
        it); nothing for a stack of the reader threads (the lock held)."""
        buffer = self._shared.pop(id(stack), None)
        if buffer is not None and self.child is not None:
            self.child.forget(buffer)

    def close(self):
        """Stop reading (pending images are skipped) and wait for the threads."""
        with self._lock:
            self._closed = True
            self._poses.clear()
            self._handed_stacks = []
            self._shared.clear()
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
        if self.child is not None:
            self.child.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
