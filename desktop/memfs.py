"""The calibration store's files in memory (firmware.store's fs interface: open(path, mode)
with read/write/close, remove(path)), for the commands that run the app on a simulated board
without a disk (serve, soak). A missing file raises OSError 2 (ENOENT), as a board's does."""


class MemFs:
    def __init__(self):
        self.files = {}

    def open(self, path, mode):
        if "w" in mode:
            self.files[path] = b""
            return _MemFile(self, path, b"")
        if path not in self.files:
            raise OSError(2, "ENOENT")
        return _MemFile(None, path, self.files[path])

    def remove(self, path):
        if path not in self.files:
            raise OSError(2, "ENOENT")
        del self.files[path]


class _MemFile:
    def __init__(self, fs, path, data):
        self.fs = fs
        self.path = path
        self.data = data

    def read(self, n=-1):  # sequential, as a file's
        d, self.data = (self.data, b"") if n < 0 else (self.data[:n], self.data[n:])
        return d

    def write(self, b):
        self.fs.files[self.path] += bytes(b)
        return len(b)

    def close(self):
        pass
