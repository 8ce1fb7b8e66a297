"""Root conftest: puts the repository on sys.path so tests can share helpers as ``tests.<module>``."""
