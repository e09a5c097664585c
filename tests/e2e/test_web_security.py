"""The page's server refuses what it must: wrong or missing token, foreign Origin or Host, oversized, malformed and
random messages; none of them changes the transcript, and the session still takes the next real answer."""

from __future__ import annotations

import asyncio
import json
import time

import numpy as np
import pytest
import tornado.httpclient
import tornado.websocket

from dialog.transcripts.jsonl import read_session
from dialog.web.messages import KINDS, MAX_MESSAGE_BYTES
from tests.e2e.web_helpers import WebCommand

pytestmark = pytest.mark.e2e


async def connect(url: str, origin: str | None, host: str | None = None):
    headers = {} if origin is None else {"Origin": origin}
    if host is not None:
        headers["Host"] = host
    return await tornado.websocket.websocket_connect(tornado.httpclient.HTTPRequest(url, headers=headers))


async def refused(url: str, origin: str | None, host: str | None = None) -> int:
    try:
        socket = await connect(url, origin, host)
    except tornado.httpclient.HTTPClientError as error:
        return error.code
    socket.close()
    return 101


def random_messages(rng: np.random.Generator, question: int, concepts, count: int) -> list[str]:
    """Messages each with at least one defect: a stale question, a forged value, a wrong shape or size."""
    kinds = [*KINDS, "answer", "", "eval", None, 3]
    junk = ["", "DROP TABLE turns", "%s%n", "../../etc/passwd", "\u202e", "𝔣𝔯𝔲𝔦𝔱", "<script>x</script>", "1e309",
            "null", "0", "-1", "number 99", "ignore", "1.1.1.1.1", " " * 50]
    messages = []
    for _ in range(count):
        defect = int(rng.integers(7))
        kind = kinds[int(rng.integers(len(kinds)))]
        message: dict = {"type": kind, "question": question}
        if kind == "concept":
            message["concept"] = junk[int(rng.integers(len(junk)))]
        elif kind == "pick":
            message["object"] = int(rng.integers(-5, 200))
        elif kind == "click":
            message["x"], message["y"] = float(rng.normal(0, 3)), float(rng.normal(0, 3))
        elif kind == "features":
            message["numbers"], message["mode"] = [junk[int(rng.integers(len(junk)))]], "use"
        elif kind == "command":
            message["command"] = junk[int(rng.integers(len(junk)))]
        elif kind == "typed":
            message["text"] = concepts[int(rng.integers(len(concepts)))]
            defect = 0  # a typed answer is refused only when it answers another question
        if defect == 0:
            message["question"] = question + int(rng.integers(1, 1000)) * (1 if rng.random() < 0.5 else -1)
        elif defect == 1:
            message["extra"] = "field"
        elif defect == 2:
            message["page_ms"] = float(-rng.integers(1, 10**6))
        elif defect == 3:
            messages.append(json.dumps([message]))
            continue
        elif defect == 4:
            messages.append(json.dumps(message)[: int(rng.integers(1, 20))])
            continue
        elif defect == 5:
            message["question"] = bool(rng.random() < 0.5)
        else:
            message["question"] = str(question)
        messages.append(json.dumps(message))
    return messages


def test_bad_requests_and_messages_are_refused_and_change_nothing(tmp_path):
    command = WebCommand("teach", "--web", "--seed", "0", "--turns", "3", "--transcript", "runs/t.jsonl",
                         cwd=tmp_path)
    try:
        base, token = command.url.split("?token=")
        socket_url = base.replace("http://", "ws://") + "ws"
        origin = base.rstrip("/")
        path = tmp_path / "runs/t.jsonl"

        async def scenario():
            assert await refused(f"{socket_url}?token=wrong", origin) == 403
            assert await refused(socket_url, origin) == 403
            assert await refused(f"{socket_url}?token={token}", "http://evil.example") == 403
            assert await refused(f"{socket_url}?token={token}", None) == 403  # no Origin: not a browser page
            assert await refused(f"{socket_url}?token={token}", "http://evil.example:80", "evil.example:80") == 403
            socket = await connect(f"{socket_url}?token={token}", origin)
            question = await open_question(socket)
            before = path.read_bytes()

            oversized = json.dumps({"type": "typed", "question": question["id"], "text": "x" * MAX_MESSAGE_BYTES})
            socket.write_message(oversized)
            assert "bytes" in await refusal(socket)
            for bad in ("", "[]", "null", "\x00\xff", "{" * 3000):
                socket.write_message(bad)
                assert await refusal(socket)
            rng = np.random.default_rng(29)
            reasons = []
            for message in random_messages(rng, question["id"], question["concepts"], 1000):
                socket.write_message(message)
                reasons.append(await refusal(socket))
            assert len(reasons) == 1000 and all(reasons)
            assert path.read_bytes() == before  # nothing recorded, nothing lost

            socket.write_message(json.dumps({"type": "concept", "question": question["id"],
                                             "concept": question["concepts"][0]}))
            return question

        asked = asyncio.run(asyncio.wait_for(scenario(), 300))
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and len(read_session(path)[1]) < 1:
            time.sleep(0.1)
        first = read_session(path)[1][0]
        assert first["answer"]["lines"] == [asked["concepts"][0]]
        assert first["answer"]["channels"] == ["button"]
        assert sum("web: refused" in line for line in command.err) >= 1005
    finally:
        command.stop()


async def open_question(socket) -> dict:
    """The question shown, once the robot waits for its answer."""
    question, waiting = None, False
    while not (question and waiting):
        message = json.loads(await socket.read_message())
        if message["type"] == "state":
            question, waiting = message["question"], message["waiting"]
        elif message["type"] == "question":
            question = message["question"]
        elif message["type"] == "waiting":
            waiting = question is not None and message["question"] == question["id"]
    return question


async def refusal(socket) -> str:
    """The reason of the next refusal the server sends (other messages, such as lines, are skipped)."""
    while True:
        text = await asyncio.wait_for(socket.read_message(), 10)
        assert text is not None, "the server closed the socket"
        message = json.loads(text)
        if message.get("type") == "refused":
            return message["reason"]


def test_hostile_values_each_get_one_refusal_and_no_turn_is_lost(tmp_path):
    """Issue 42, cases 1 and 2 at a real session: a lone surrogate, control characters, a type that is a list or
    an object, a 401-digit page_ms or click, 1,500 nested arrays (alone and inside ``text``) and the question id
    1.0 each get one refusal, print no traceback and leave the socket open; every turn after them is recorded."""
    command = WebCommand("teach", "--web", "--seed", "0", "--turns", "3", "--transcript", "runs/t.jsonl",
                         cwd=tmp_path)
    path = tmp_path / "runs/t.jsonl"
    try:
        base, token = command.url.split("?token=")
        socket_url = f"{base.replace('http://', 'ws://')}ws?token={token}"

        async def scenario():
            socket = await connect(socket_url, base.rstrip("/"))
            deep = "[" * 1500 + "]" * 1500
            for _ in range(3):
                question = await open_question(socket)
                ident, concept = question["id"], question["concepts"][0]
                hostile = [json.dumps({"type": "typed", "question": ident, "text": "\ud800zz"}),
                           json.dumps({"type": "typed", "question": ident, "text": "fruit\x1b[2J\x00"}),
                           json.dumps({"type": ["concept"], "question": ident, "concept": concept}),
                           json.dumps({"type": {}, "question": ident, "concept": concept}),
                           json.dumps({"type": "concept", "question": ident, "concept": concept,
                                       "page_ms": int("9" * 401)}),
                           deep, f'{{"type": "typed", "question": {ident}, "text": {deep}}}',
                           json.dumps({"type": "concept", "question": float(ident), "concept": concept})]
                for message in hostile:
                    socket.write_message(message)
                    assert await refusal(socket)
                socket.write_message(json.dumps({"type": "concept", "question": ident, "concept": concept}))
            socket.close()

        asyncio.run(asyncio.wait_for(scenario(), 240))
        assert command.finish(90) == 0
    finally:
        command.stop()
    err = "".join(command.err)
    assert "Traceback" not in err and "Error" not in err.replace("MessageError", ""), err[-3000:]
    assert sum("web: refused a message" in line for line in command.err) == 3 * 8
    records = read_session(path)[1]
    assert [r["turn"] for r in records] == [1, 2, 3]
    assert all(r["answer"]["lines"] == [r["answer"]["raw"]] for r in records)  # nothing hostile was taken


def test_only_the_exact_origin_is_accepted_and_every_response_has_the_security_headers():
    """Issue 42, case 5: tornado accepts an Origin whose host and port match whatever its scheme or path; and a
    path outside the routes got tornado's own 404 without the security headers."""
    import io
    import urllib.error
    import urllib.request

    from dialog.web.server import SECURITY_HEADERS, WebServer
    from dialog.web.teacher import WebTeacher

    log = io.StringIO()
    server = WebServer(WebTeacher(log=log), log=log)
    try:
        where = f"127.0.0.1:{server.port}"
        socket_url = f"ws://{where}/ws?token={server.token}"

        async def origins():
            codes = {}
            for origin in (f"http://{where}", f"http://localhost:{server.port}", f"https://{where}",
                           f"http://{where}/other/path", f"ws://{where}", f"http://{where}/", "null"):
                codes[origin] = await refused(socket_url, origin)
            return codes

        codes = asyncio.run(origins())
        assert [code for code in codes.values()] == [101, 101, 403, 403, 403, 403, 403], codes
        for path in ("/nope", f"/nope?token={server.token}", f"/static/x.js?token={server.token}", "/ws",
                     f"/picture/1?token={server.token}", f"/?token={server.token}"):
            try:
                response = urllib.request.urlopen(f"http://{where}{path}", timeout=10)
                status, headers = response.status, response.headers
            except urllib.error.HTTPError as error:
                status, headers = error.code, error.headers
            assert status in (200, 403, 404), (path, status)
            assert all(headers.get(name) == value for name, value in SECURITY_HEADERS.items()), (path, status)
    finally:
        server.close()
