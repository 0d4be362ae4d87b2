"""A stand-in for OpenEXR.File that fails like a full disk, for the atomic-write tests."""


class FailingExrFile:
    """Stands in for OpenEXR.File: writes half a file, then fails like a full disk."""

    def __init__(self, header, channels):
        pass

    def write(self, path):
        with open(path, "wb") as stream:
            stream.write(b"v/1\x01half")
        raise RuntimeError("No space left on device")
