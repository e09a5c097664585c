"""--web's options: loopback unless --allow-remote, the others only with --web, --origin a scheme and host."""

import argparse

import pytest

from dialog.web.server import check_host, is_loopback, public_origin
from dialog.web.session import add_web_options, check_web_options
from learning.errors import SettingsError


def options(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_web_options(parser)
    return parser.parse_args(argv)


@pytest.mark.parametrize("argv, says", [
    (("--web", "--host", "0.0.0.0"), "--host 0.0.0.0 would let other machines reach the page"),
    (("--web", "--host", "192.168.1.5"), "or add --allow-remote"),
    (("--port", "8000"), "--port only goes with --web"),
    (("--allow-remote", "--no-3d"), "--allow-remote, --no-3d only go with --web"),
    (("--web", "--origin", "https://study.example.org/path"), "accepted: scheme and host only"),
    (("--web", "--origin", "ftp://study.example.org"), "accepted: scheme and host only"),
])
def test_unsafe_or_stray_options_are_refused_in_one_line(argv, says):
    with pytest.raises(SettingsError, match=says):
        check_web_options(options(*argv))


@pytest.mark.parametrize("argv", [(), ("--web",), ("--web", "--host", "localhost", "--port", "0"),
                                  ("--web", "--host", "0.0.0.0", "--allow-remote"),
                                  ("--web", "--origin", "https://study.example.org")])
def test_safe_options_pass(argv):
    check_web_options(options(*argv))


def test_loopback_and_origins():
    assert is_loopback("127.0.0.1") and is_loopback("::1") and is_loopback("localhost")
    assert not is_loopback("0.0.0.0") and not is_loopback("example.org")
    check_host("0.0.0.0", allow_remote=True)
    assert public_origin("https://study.example.org") == ("https", "study.example.org")
