"""The application: dialog manager, teachers, transcripts and the ``teachbot`` command."""
