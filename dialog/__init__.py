"""The application: dialog manager, teachers, transcripts and the ``teachbot`` command."""

from importlib import metadata


def software_version() -> str:
    """"teachbot X.Y.Z" as installed (what ``teachbot --version`` prints and study records name)."""
    try:
        return f"teachbot {metadata.version('teachbot')}"
    except metadata.PackageNotFoundError:
        return "teachbot (not installed)"
