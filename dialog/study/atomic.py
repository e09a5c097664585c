"""Writing a study record whole or not at all, and never over recorded answers."""

from __future__ import annotations

import os
from pathlib import Path

from dialog.output_paths import writing
from learning.errors import OutputPathError


def write_atomically(path: Path, text: str, what: str, *, replace: bool = True) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename: the record is there whole or not at all.

    With ``replace=False`` (recorded answers) an existing ``path`` is never written over: the temporary file
    is linked into place, which fails if the name is taken, and the refusal names the file. The temporary file
    is removed however the call ends; text that is not valid Unicode (a lone surrogate) is a ``ValueError``
    before anything is opened (the callers check what people type first: ``questionnaire.text_problem``).
    """
    data = text.encode("utf-8")  # text that can't be encoded fails here, before any file is opened
    temporary = path.with_name(f".{path.name}.tmp")
    with writing(path, what):
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            with open(temporary, "wb") as handle:
                handle.write(data)
                handle.flush()
                os.fsync(handle.fileno())
            if replace:
                os.replace(temporary, path)
                return
            try:
                os.link(temporary, path)
            except FileExistsError:
                raise OutputPathError(f"{path}: already holds the {what}; teachbot never writes over recorded "
                                      "answers (run the condition again with --condition NAME --again to keep "
                                      "them as *.superseded-N)") from None
        finally:  # the temporary file never outlives the call, whatever happened
            temporary.unlink(missing_ok=True)
