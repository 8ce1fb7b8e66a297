"""The project's offline tools (run from a checkout; not part of the installed ``curv`` package)."""
