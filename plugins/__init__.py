"""Built-in sphcore plugins (installed as the import package ``sphcore_plugins``).

Each is registered through the entry-point group ``sphcore`` in pyproject.toml, exactly
like a third-party plugin; the core never imports this package.
"""
