"""Saving a figure so that a failure never leaves half a file: the plot is written under a
temporary name beside the target and renamed into place only when complete (the rule every
scratchlight output follows; src/io/AtomicFile.h)."""
import os


def savefig(fig, path, **kwargs):
    path = os.fspath(path)
    folder, name = os.path.split(path)
    stem, ext = os.path.splitext(name)
    temp = os.path.join(folder, ".%s.tmp-%d%s" % (stem, os.getpid(), ext))
    try:
        fig.savefig(temp, format=ext.lstrip(".") or None, **kwargs)
        with open(temp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(temp, path)
    except BaseException:
        if os.path.exists(temp):
            os.remove(temp)
        raise
