"""The numerical core: numpy arrays and frozen dataclasses in, out; no file I/O, no CLI."""
