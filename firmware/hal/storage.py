"""Small-file storage for the firmware: a directory of files, or a dict in RAM.

``FileStorage`` works on MicroPython's VFS (LittleFS, FAT) and on CPython: ``write`` creates or
replaces a file, ``rename`` replaces the destination (removing it first where the file system
refuses to rename over an existing file), so a configuration is committed by writing a
temporary file and renaming it. ``MemStorage`` keeps the files in a dict, for tests and for an
emulated board without a state directory.
"""

import os


class FileStorage:
    def __init__(self, root: str = "") -> None:
        self.root = root

    def _path(self, name: str) -> str:
        return self.root + "/" + name if self.root else name

    def read(self, name: str) -> "bytes | None":
        try:
            with open(self._path(name), "rb") as f:
                return f.read()
        except OSError:
            return None

    def write(self, name: str, data: bytes) -> None:
        with open(self._path(name), "wb") as f:
            f.write(data)

    def rename(self, old: str, new: str) -> None:
        try:
            os.rename(self._path(old), self._path(new))
        except OSError:  # FAT will not rename over an existing file
            self.remove(new)
            os.rename(self._path(old), self._path(new))

    def remove(self, name: str) -> None:
        try:  # noqa: SIM105 (MicroPython has no contextlib)
            os.remove(self._path(name))
        except OSError:
            pass


class MemStorage:
    def __init__(self) -> None:
        self.files: "dict[str, bytes]" = {}
        self.writes = 0

    def read(self, name: str) -> "bytes | None":
        return self.files.get(name)

    def write(self, name: str, data: bytes) -> None:
        self.files[name] = bytes(data)
        self.writes += 1

    def rename(self, old: str, new: str) -> None:
        self.files[new] = self.files.pop(old)

    def remove(self, name: str) -> None:
        self.files.pop(name, None)
