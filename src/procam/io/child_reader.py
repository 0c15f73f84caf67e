"""Image files read by a forked child process into shared memory: the reading runs under its own interpreter lock.

A multi-pose ``procam calibrate`` reads the next pose's PNGs while it processes this one
(:class:`procam.stream.Prefetcher`).  Read by threads of the same process, the two compete for Python's interpreter
lock: every PNG needs it several times between the calls that let it go (inflating, undoing the filter), and a
thread that wants it back waits until the thread running Python (an import, a fit, the many small numpy calls of
the checks) lets it go -- up to Python's switch interval (5 ms) each time.  A child process has a lock of its own,
so the two sides only share the cores.

:meth:`ChildReader.start` forks the child while the process still runs one thread, before numpy, OpenCV and their
thread pools are loaded (a fork beside running threads can copy a lock another thread holds; Python 3.12 warns
about it): so the command line starts it first thing (:func:`procam.cli.main`), and it returns None anywhere it
cannot (not Linux, more than one thread running, no ``memfd_create`` or descriptor passing, a failed fork), where
the caller reads with threads.  The child then waits for commands on a socket: read these files into that shared
buffer (a ``memfd`` the parent made and passed along, mapped by both), and says when a pose is done, or that it
failed (the parent then reads the pose itself, so every error is the same as without the child, word for word).
It ignores Ctrl-C (the parent stops it), leaves with ``os._exit`` (none of the parent's exit handlers or buffered
output runs twice), and exits when the parent closes the socket, or dies.
"""

from __future__ import annotations

import os
import sys

#: bytes of a command or a reply the socket carries at most (a command lists a pose's files)
_MAX_MESSAGE = 1 << 20


def _single_threaded() -> bool:
    """Whether this process runs one thread (Linux's count, which includes threads Python did not start)."""
    try:
        with open("/proc/self/status", "rb") as f:
            for line in f:
                if line.startswith(b"Threads:"):
                    return int(line.split()[1]) == 1
    except (OSError, ValueError, IndexError):
        pass
    return False


class ChildReader:
    """A forked child that reads image files into shared buffers on command (the module docstring).

    Use :meth:`start` (None where it cannot run), :meth:`new_buffer` for a stack the child can fill,
    :meth:`submit` to have it filled, :meth:`wait` for the result, :meth:`close` to stop the child.
    """

    def __init__(self, sock, pid: int):
        self._sock = sock
        self.pid = pid
        self._buffers = 0        # shared buffers made so far (their ids)
        self._pending_fd = {}    # buffer id -> memfd not yet passed to the child
        self._tickets = 0
        self._replies: dict[int, bool] = {}
        self._dead = False

    @classmethod
    def start(cls, threads: int | None = None, *, when_threaded: bool = False) -> "ChildReader | None":
        """Fork the child reader, with ``threads`` reader threads of its own (default ``min(2, cpu_count)``); None
        where it cannot run (the module docstring), or this process runs more than one thread (unless
        ``when_threaded``: for tests, which run beside their runner's threads)."""
        import socket

        if not sys.platform.startswith("linux") or not all(
                hasattr(x, n) for x, n in ((os, "fork"), (os, "memfd_create"), (socket, "send_fds"),
                                          (socket, "SOCK_SEQPACKET"))):
            return None
        if not when_threaded and not _single_threaded():
            return None
        try:
            parent, child = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        except OSError:
            return None
        n = threads if threads is not None else min(2, os.cpu_count() or 1)
        try:
            pid = os.fork()
        except OSError:
            parent.close()
            child.close()
            return None
        if pid == 0:  # pragma: no cover - runs in the child (tests check what it does, from the parent)
            code = 0
            try:
                parent.close()
                _serve(child, max(1, int(n)))
            except BaseException:
                code = 1
            finally:
                os._exit(code)
        child.close()
        return cls(parent, pid)

    # -- the parent's side ---------------------------------------------------------------------
    def new_buffer(self, nbytes: int):
        """A new shared buffer of ``nbytes`` (an ``mmap``) and its id, for :meth:`submit`; None when no memory can
        be had (the caller then reads without the child)."""
        import mmap

        if self._dead:
            return None
        try:
            fd = os.memfd_create("procam-stack", getattr(os, "MFD_CLOEXEC", 0))
        except OSError:
            return None
        try:
            os.ftruncate(fd, max(1, int(nbytes)))
            buf = mmap.mmap(fd, max(1, int(nbytes)))
        except (OSError, ValueError):
            os.close(fd)
            return None
        self._buffers += 1
        self._pending_fd[self._buffers] = fd
        return buf, self._buffers

    def submit(self, files, buffer_id: int, shape, dtype: str, gray: bool = True) -> int | None:
        """Have the child read ``files`` into the buffer ``buffer_id`` as an array of ``shape`` and ``dtype``
        (``"uint8"``/``"uint16"``), one file per frame (:func:`procam.io.images.read_image`); returns the ticket for
        :meth:`wait`, or None when the child is gone."""
        import json
        import socket

        if self._dead:
            return None
        self._tickets += 1
        msg = json.dumps({"ticket": self._tickets, "files": [str(f) for f in files], "buffer": int(buffer_id),
                          "shape": [int(s) for s in shape], "dtype": str(dtype), "gray": bool(gray)}).encode()
        if len(msg) > _MAX_MESSAGE:
            return None
        fd = self._pending_fd.pop(buffer_id, None)
        try:
            if fd is not None:
                socket.send_fds(self._sock, [msg], [fd])
            else:
                self._sock.sendall(msg)
        except OSError as e:
            import errno

            self._dead = e.errno != errno.EMSGSIZE  # a command too long for one message: that pose is read here
            return None
        finally:
            if fd is not None:
                os.close(fd)
        return self._tickets

    def forget(self, buffer_id: int) -> None:
        """The child unmaps the buffer ``buffer_id`` (it will not be filled again): its memory is freed once this
        process lets go of it too."""
        import json

        fd = self._pending_fd.pop(buffer_id, None)
        if fd is not None:  # never passed to the child
            os.close(fd)
            return
        if not self._dead:
            try:
                self._sock.sendall(json.dumps({"forget": int(buffer_id)}).encode())
            except OSError:
                self._dead = True

    def wait(self, ticket: int | None) -> bool:
        """Whether the child read the files of ``ticket`` (all of them, into the buffer); False when it could not
        (a file it could not read, one of another size, the child gone): the caller reads them itself."""
        if ticket is None:
            return False
        while ticket not in self._replies and not self._dead:
            try:
                reply = self._sock.recv(64)
            except OSError:
                reply = b""
            if not reply:
                self._dead = True
                break
            got, ok = reply.decode().split()
            self._replies[int(got)] = ok == "1"
        return self._replies.pop(ticket, False)

    def close(self) -> None:
        """Stop the child (at once: a pose it is reading is not needed any more) and reap it."""
        import signal

        if self.pid:
            for fd in self._pending_fd.values():
                os.close(fd)
            self._pending_fd.clear()
            self._sock.close()
            try:
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:  # pragma: no cover - already gone and reaped elsewhere
                pass
            try:
                os.waitpid(self.pid, 0)
            except ChildProcessError:  # pragma: no cover
                pass
            self.pid = 0
            self._dead = True


def _serve(sock, threads: int) -> None:  # pragma: no cover - runs in the child (tested through the parent)
    """The child's loop: read the commands of :meth:`ChildReader.submit` until the parent closes the socket."""
    import json
    import signal
    import socket

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole process group: the parent stops us
    buffers = {}
    while True:
        msg, fds, _, _ = socket.recv_fds(sock, _MAX_MESSAGE, 1)
        if not msg:
            return
        cmd = json.loads(msg)
        if "forget" in cmd:
            gone = buffers.pop(cmd["forget"], None)
            if gone is not None:
                try:
                    gone.close()
                except BufferError:  # an array of it not yet collected: unmapped when it is
                    pass
            continue
        if fds:
            import mmap

            buffers[cmd["buffer"]] = mmap.mmap(fds[0], os.fstat(fds[0]).st_size)
            os.close(fds[0])
        ok = _fill(buffers.get(cmd["buffer"]), cmd, threads)
        sock.sendall(f"{cmd['ticket']} {int(ok)}".encode())


def _fill(buf, cmd: dict, threads: int) -> bool:  # pragma: no cover - runs in the child
    """Read the command's files into ``buf`` (:func:`procam.io.images.read_images` into it, ``threads`` at once);
    whether every one was read, of the stack's frame size and type."""
    import numpy as np

    from . import images

    if buf is None:
        return False
    shape, dtype = tuple(cmd["shape"]), np.dtype(cmd["dtype"])
    if len(cmd["files"]) != shape[0] or int(np.prod(shape)) * dtype.itemsize > len(buf):
        return False
    stack = np.frombuffer(buf, dtype, int(np.prod(shape))).reshape(shape)
    try:
        images.read_images(cmd["files"], cmd["gray"], threads, out=stack)
    except Exception:  # a file it cannot read, or of another size or type: the parent reads the pose, and says so
        return False
    return True
