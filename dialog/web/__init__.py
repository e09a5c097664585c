"""Teaching in the browser (``--web``): one page on 127.0.0.1, the session behind it (docs/web.md)."""
