"""Writing files in place: whole or not at all."""
from __future__ import annotations

import os
import tempfile


def write_atomically(path, data):
    """Writes bytes to `path` through a temporary file in its directory and a rename; refuses to
    replace anything but a regular file."""
    path = os.fspath(path)
    if os.path.islink(path) or (os.path.lexists(path) and not os.path.isfile(path)):
        raise FileExistsError(f"{path}: exists and is not a regular file; not replaced")
    directory = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix="." + os.path.basename(path) + ".", dir=directory)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)  # mkstemp's 0600 would make results private
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise
