"""The meshcat viewer without a browser: reading PyBullet, meshes, the recording, the server, the observer."""

from __future__ import annotations

import base64
import re
import socket
import threading
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pybullet as p
import pybullet_data
import pytest
import umsgpack

from bullet_world.viewer.meshcat_objects import MeshcatScene, object_jsons
from bullet_world.viewer.meshes import MeshFileError, parse_obj
from bullet_world.viewer.mirror import Viewer
from bullet_world.viewer.recording import Recording
from bullet_world.viewer.scene import Look, WorldReader, pose_matrix, translation
from bullet_world.viewer.server import LocalServer
from bullet_world.viewer.tap import add_step_listener, is_tapped, remove_step_listener

RED, GREEN, MAGENTA = (0.9, 0.05, 0.05, 1.0), (0.05, 0.75, 0.1, 1.0), (0.85, 0.05, 0.85, 1.0)


class BareWorld:
    """A PyBullet client with a counter and a few primitive objects: what the viewer needs of a World."""

    def __init__(self, arm: bool = False):
        self.client = p.connect(p.DIRECT)
        p.setGravity(0, 0, -9.81, physicsClientId=self.client)
        self.counter_body = self.primitive(p.GEOM_BOX, (0.6, 0.4, 0.02), (0.6, 0.6, 0.6, 1.0), (0, 0, -0.02), mass=0)
        self.object_bodies: list[int] = []
        self.robot = None
        if arm:
            body = p.loadURDF(pybullet_data.getDataPath() + "/franka_panda/panda.urdf", [0, -0.5, 0],
                              useFixedBase=True, physicsClientId=self.client)
            self.robot = SimpleNamespace(body_id=body)

    def primitive(self, shape: int, size, rgba, position, yaw: float = 0.0, mass: float = 1.0) -> int:
        if shape == p.GEOM_BOX:
            visual = p.createVisualShape(shape, halfExtents=list(size), rgbaColor=list(rgba),
                                         physicsClientId=self.client)
            collision = p.createCollisionShape(shape, halfExtents=list(size), physicsClientId=self.client)
        elif shape == p.GEOM_SPHERE:
            visual = p.createVisualShape(shape, radius=size[0], rgbaColor=list(rgba), physicsClientId=self.client)
            collision = p.createCollisionShape(shape, radius=size[0], physicsClientId=self.client)
        else:
            visual = p.createVisualShape(shape, radius=size[0], length=size[1], rgbaColor=list(rgba),
                                         physicsClientId=self.client)
            collision = p.createCollisionShape(shape, radius=size[0], height=size[1], physicsClientId=self.client)
        return p.createMultiBody(mass, collision, visual, list(position), p.getQuaternionFromEuler([0, 0, yaw]),
                                 physicsClientId=self.client)

    def add(self, *args, **kwargs) -> int:
        body = self.primitive(*args, **kwargs)
        self.object_bodies.append(body)
        return body

    def three_objects(self) -> list[int]:
        return [self.add(p.GEOM_BOX, (0.06, 0.04, 0.04), RED, (-0.3, 0.05, 0.04), yaw=0.4),
                self.add(p.GEOM_SPHERE, (0.05,), GREEN, (0.0, 0.1, 0.05)),
                self.add(p.GEOM_CYLINDER, (0.045, 0.12), MAGENTA, (0.3, 0.0, 0.06))]

    def textured_cube(self, folder: Path, rgb, position, size: float = 0.1) -> tuple[int, str]:
        """An object from a mesh file with texture coordinates, and a one-colour PNG for its texture."""
        from PIL import Image

        obj, png = folder / "cube.obj", folder / "cube.png"
        corners = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
        quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
        lines = [f"v {x} {y} {z}" for x, y, z in corners] + ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1"]
        lines += ["f " + " ".join(f"{v}/{k + 1}" for k, v in enumerate(quad)) for quad in quads]
        obj.write_text("\n".join(lines) + "\n")
        Image.new("RGB", (8, 8), tuple(rgb)).save(png)
        visual = p.createVisualShape(p.GEOM_MESH, fileName=str(obj), meshScale=[size] * 3, rgbaColor=[1, 1, 1, 1],
                                     physicsClientId=self.client)
        collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=[size / 2] * 3, physicsClientId=self.client)
        body = p.createMultiBody(0.2, collision, visual, list(position), physicsClientId=self.client)
        self.object_bodies.append(body)
        return body, str(png)

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)


@pytest.fixture
def bare():
    world = BareWorld()
    yield world
    world.close()


def test_reader_reports_each_primitive_with_its_size_colour_and_pose(bare):
    box, sphere, cylinder = bare.three_objects()
    capsule = bare.add(p.GEOM_CAPSULE, (0.02, 0.1), (0.2, 0.2, 0.9, 1.0), (0.1, -0.2, 0.1))
    reader = WorldReader(bare)
    frame = reader.frame()
    assert len(reader.object_nodes) == 4 and all(node.startswith("objects/") for node in reader.object_nodes)
    looks = [frame[node][0][0] for node in reader.object_nodes]
    assert [look.shape for look in looks] == ["box", "sphere", "cylinder", "capsule"]
    assert looks[0].size == pytest.approx((0.12, 0.08, 0.08)) and looks[1].size == pytest.approx((0.05,))
    assert looks[2].size == pytest.approx((0.045, 0.12)) and looks[3].size == pytest.approx((0.02, 0.1))
    assert looks[0].rgba == pytest.approx(RED, abs=1e-3) and looks[2].rgba == pytest.approx(MAGENTA, abs=1e-3)
    assert frame["kitchen/counter"][0][0].size == pytest.approx((1.2, 0.8, 0.04))
    expected = pose_matrix(*p.getBasePositionAndOrientation(box, physicsClientId=bare.client))
    assert np.allclose(frame[reader.object_nodes[0]][1], expected)
    assert np.allclose(frame[reader.object_nodes[3]][1][:3, 3], (0.1, -0.2, 0.1))
    assert capsule and sphere and cylinder


def test_a_textured_mesh_keeps_its_texture_and_texture_coordinates(bare, tmp_path):
    body, png = bare.textured_cube(tmp_path, (255, 128, 0), (0, 0, 0.05))
    reader = WorldReader(bare, appearance=lambda b: (png, None) if b == body else ("", None))
    (look,) = reader.frame()[reader.object_nodes[0]][0]
    assert (look.shape, look.texture, look.size) == ("mesh", png, pytest.approx((0.1, 0.1, 0.1)))
    (json,) = object_jsons(look)
    (geometry,), (material,) = json["geometries"], json["materials"]
    assert set(geometry["data"]["attributes"]) == {"position", "uv"} and len(geometry["data"]["attributes"]) == 2
    assert material["map"] == json["textures"][0]["uuid"]
    assert json["images"][0]["url"].startswith("data:image/png;base64,")
    plain = WorldReader(bare).frame()  # without an appearance hint: PyBullet's own colour, no texture
    assert all(not looks[0].texture for looks, _ in plain.values())


def test_reader_follows_the_panda_link_frames_and_its_base_frame():
    world = BareWorld(arm=True)
    try:
        arm = world.robot.body_id
        for joint, angle in enumerate((0.3, -0.5, 0.2, -2.0, 0.1, 1.6, 0.7)):
            p.resetJointState(arm, joint, angle, physicsClientId=world.client)
        frame = WorldReader(world).frame()
        robot = {node: value for node, value in frame.items() if node.startswith("robot/")}
        assert set(robot) == {f"robot/link{i}" for i in (-1, 0, 1, 2, 3, 4, 5, 6, 8, 9, 10)}
        assert Path(robot["robot/link3"][0][0].file).name == "link4.obj"  # PyBullet link 3 is panda_link4
        state = p.getLinkState(arm, 3, computeForwardKinematics=True, physicsClientId=world.client)
        assert np.allclose(robot["robot/link3"][1], pose_matrix(state[4], state[5]))
        # the base's centre of mass sits 5 cm above its URDF frame: the node is at the frame, where it was loaded
        assert np.allclose(robot["robot/link-1"][1][:3, 3], (0, -0.5, 0), atol=1e-9)
    finally:
        world.close()


def test_reader_notices_a_reused_body_id_with_a_new_look(bare):
    first = bare.add(p.GEOM_BOX, (0.05, 0.05, 0.05), RED, (0, 0, 0.05))
    reader = WorldReader(bare)
    old = reader.frame()
    p.removeBody(first, physicsClientId=bare.client)
    bare.object_bodies.clear()
    second = bare.add(p.GEOM_SPHERE, (0.03,), GREEN, (0.1, 0, 0.03))
    new = reader.frame(refresh=True)
    assert second == first, "PyBullet reuses the id (the case this test is about)"
    (old_node,), (new_node,) = ([n for n in f if n.startswith("objects/")] for f in (old, new))
    assert old_node != new_node and new[new_node][0][0].shape == "sphere"


def test_obj_quads_become_triangles_with_their_uvs(tmp_path):
    path = tmp_path / "quad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
                    "f 1/1/1 2/2/1 3/3/1 4/4/1\nf -4/1 -2/3 -1/4\n")
    mesh = parse_obj(str(path), with_uvs=True)
    assert mesh.faces.shape == (3, 3) and mesh.positions.shape == (4, 3) and mesh.uvs.shape == (4, 2)
    corners = mesh.positions[mesh.faces]
    assert np.allclose(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2], 1.0)
    assert np.allclose(mesh.uvs, mesh.positions[:, :2])  # each corner kept its own texture coordinate
    plain = parse_obj(str(path))
    assert plain.uvs is None and plain.faces.shape == (3, 3)


def test_broken_obj_files_are_named_with_the_problem(tmp_path):
    cases = {"missing.obj": None, "letters.obj": "v 0 0 x\nf 1 1 1\n", "faces.obj": "v 0 0 0\nv 1 0 0\nf 1 2\n",
             "index.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"}
    messages = {"missing.obj": "cannot read", "letters.obj": "not a number", "faces.obj": "fewer than 3 corners",
                "index.obj": "does not exist"}
    for name, text in cases.items():
        if text is not None:
            (tmp_path / name).write_text(text)
        with pytest.raises(MeshFileError, match=messages[name]) as raised:
            parse_obj(str(tmp_path / name))
        assert name in str(raised.value) and "\n" not in str(raised.value)


def test_recording_keeps_keys_only_where_poses_change_and_versions_where_looks_change():
    still, moving = Look("box", (0.1, 0.1, 0.1), RED), Look("sphere", (0.05,), GREEN)
    recording = Recording(fps=10)
    for step in range(30):  # 3 s: the sphere moves from 1 s to 2 s and holds otherwise
        x = min(max(step - 10, 0), 10) / 10
        frame = {"a": ((still,), translation(0, 0, 0)), "b": ((moving,), translation(x, 0, 0))}
        if step >= 20:
            frame["a"] = ((Look("box", (0.2, 0.1, 0.1), RED),), translation(0, 0, 0))  # grows at 2 s
        recording.add(frame, step / 10)
    a1, b, a2 = recording.versions
    assert (a1.node, a1.start, a1.end, len(a1.keys)) == ("a", 0, 20, 1)
    assert (a2.start, a2.end) == (20, None)
    frames = [number for number, _ in b.keys]
    assert frames[:2] == [0, 10] and frames[-1] == 20 and len(frames) == 12  # hold, then one key per move
    assert np.allclose(b.keys[1][1], b.keys[0][1]) and np.allclose(b.keys[-1][1][:3, 3], (1, 0, 0))


class FakeNode:
    def __init__(self, calls, path):
        self.calls, self.path = calls, path

    def __getitem__(self, name):
        return FakeNode(self.calls, f"{self.path}/{name}")

    def set_object(self, obj):
        self.calls.append(("object", self.path, obj.lower()["object"]["type"]))

    def set_transform(self, matrix):
        self.calls.append(("transform", self.path))

    def delete(self):
        self.calls.append(("delete", self.path))


def test_meshcat_scene_sends_geometry_once_then_only_the_nodes_that_moved():
    calls: list = []
    scene = MeshcatScene(FakeNode(calls, ""))
    box, ball = (Look("box", (0.1, 0.1, 0.1), RED),), (Look("sphere", (0.05,), GREEN),)
    scene.apply({"a": (box, translation(0, 0, 0)), "b": (ball, translation(1, 0, 0))})
    assert sorted(c[0] for c in calls) == ["object", "object", "transform", "transform"]
    calls.clear()
    scene.apply({"a": (box, translation(0, 0, 0)), "b": (ball, translation(1.1, 0, 0))})
    assert calls == [("transform", "/world/b")]
    calls.clear()
    scene.apply({"b": (ball, translation(1.1, 0, 0))})
    assert calls == [("delete", "/world/a")]


def test_step_listener_runs_after_each_step_of_its_own_client_only(bare):
    other = p.connect(p.DIRECT)
    seen = []

    def listener():
        seen.append(1)

    try:
        add_step_listener(bare.client, listener)
        assert is_tapped()
        for _ in range(3):
            p.stepSimulation(physicsClientId=bare.client)
        p.stepSimulation(physicsClientId=other)
        assert len(seen) == 3
    finally:
        remove_step_listener(bare.client, listener)
        p.disconnect(other)
    assert not is_tapped()
    p.stepSimulation(physicsClientId=bare.client)
    assert len(seen) == 3


def _listening_addresses(port: int) -> set[str]:
    """Local addresses of LISTEN sockets on ``port`` (Linux /proc/net/tcp and tcp6)."""
    found = set()
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        lines = Path(table).read_text().splitlines()[1:] if Path(table).exists() else []
        for line in lines:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:
                found.add(address)
    return found


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="reads the socket table of Linux")
def test_server_listens_on_127_0_0_1_only():
    server = LocalServer()
    try:
        web_port = int(re.search(r":(\d+)/", server.web_url).group(1))
        zmq_port = int(server.zmq_url.rsplit(":", 1)[1])
        assert server.web_url.startswith("http://127.0.0.1:") and server.zmq_url.startswith("tcp://127.0.0.1:")
        for port in (web_port, zmq_port):
            assert _listening_addresses(port) == {"0100007F"}  # 127.0.0.1, and no IPv6 or wildcard socket
        with socket.create_connection(("127.0.0.1", web_port), timeout=5):
            pass
    finally:
        server.stop()
    assert server.process.poll() is not None


def test_live_viewer_sends_the_arm_links_as_they_move_and_nothing_else():
    world = BareWorld(arm=True)
    world.three_objects()
    viewer = Viewer(world, live_fps=1000.0)
    try:
        viewer.thread.submit(lambda: None).result(timeout=60)
        sent = dict(viewer.thread.scene.sent)
        p.setJointMotorControlArray(world.robot.body_id, list(range(7)), p.POSITION_CONTROL,
                                    targetPositions=[0.5, -0.3, 0.2, -2.0, 0.0, 1.5, 0.5], physicsClientId=world.client)
        for _ in range(120):
            p.stepSimulation(physicsClientId=world.client)
        viewer.thread.submit(lambda: None).result(timeout=60)
        after = viewer.thread.scene.sent
        assert after["objects"] == sent["objects"] and after["deletes"] == 0
        assert after["transforms"] > sent["transforms"]
        assert viewer.thread.frames_applied >= 2 and viewer.url.startswith("http://127.0.0.1:")
    finally:
        viewer.close()
        world.close()
    assert not is_tapped()


def test_a_live_view_that_dies_warns_once_and_the_session_goes_on(bare, capsys):
    box, _, _ = bare.three_objects()
    viewer = Viewer(bare, reply_timeout_s=0.5, record=True)
    try:
        viewer.on_scene(None)
        viewer.thread.submit(lambda: None).result(timeout=60)
        viewer.thread.server.process.kill()  # the server dies under the session
        for step in range(5):
            p.resetBasePositionAndOrientation(box, [0.1 * step, 0, 0.04], [0, 0, 0, 1], physicsClientId=bare.client)
            viewer.on_question({"kind": "label", "object": 1}, "What is this (object 1)?")
            viewer.thread.submit(lambda: None).result(timeout=60)
        assert viewer.thread.error and not viewer.thread.live
        viewer.on_turn({"action": {"kind": "none"}})
        assert viewer.recording.samples > 5  # the recording went on
    finally:
        viewer.close()
    warnings = capsys.readouterr().err.strip().splitlines()
    assert len(warnings) == 1 and "the session goes on without the live view" in warnings[0]


def test_drain_waits_until_meshcat_has_the_question_and_gives_up_after_its_time(bare):
    bare.three_objects()
    viewer = Viewer(bare)
    try:
        assert viewer.thread.drain(60)
        before = dict(viewer.thread.scene.sent)
        viewer.on_question({"kind": "label", "object": 1}, "What is this (object 1)?")
        assert viewer.thread.drain(60)
        assert viewer.thread.scene.sent["objects"] > before["objects"]  # the highlight and the texts: sent
        release = threading.Event()
        viewer.thread.submit(release.wait)  # a meshcat thread that is stuck
        assert not viewer.thread.drain(0.2)
        release.set()
        assert viewer.thread.drain(60)
    finally:
        viewer.close()


def test_observer_highlights_the_asked_object_and_shows_the_dialog(bare):
    bare.three_objects()
    viewer = Viewer(bare, live=False)
    try:
        viewer.on_scene(None)
        frame = viewer.frame()
        labels = {node: looks[0] for node, (looks, _) in frame.items() if node.startswith("labels/")}
        assert sorted(look.text for look in labels.values()) == ["1", "2", "3"]
        viewer.on_question(SimpleNamespace(kind="label", object_index=1, concept=None), "What is this (object 2)?")
        frame = viewer.frame()
        sphere = np.asarray(p.getBasePositionAndOrientation(bare.object_bodies[1], physicsClientId=bare.client)[0])
        assert np.allclose(frame["overlay/asked"][1][:3, 3], sphere, atol=1e-6)
        asked = [looks[0].text for node, (looks, _) in frame.items()
                 if node.startswith("labels/") and looks[0].style == "label-asked"]
        assert asked == ["2"] and frame["overlay/question"][0][0].text == "Robot: What is this (object 2)?"
        viewer.on_answer(SimpleNamespace(kind="label"), SimpleNamespace(raw="a fruit", kind="answer", value="fruit"))
        assert viewer.frame()["overlay/answer"][0][0].text == "Teacher: a fruit"
        viewer.on_turn({"turn": 1})
        viewer.on_turn({"action": {"kind": "demo", "concept": "drink"}, "question": "Can you show me a drink?",
                        "answer": {"raw": "3", "value": 2}})  # no question events: the record tells
        frame = viewer.frame()
        assert "overlay/asked" not in frame and frame["overlay/question"][0][0].text.endswith("show me a drink?")
        assert np.allclose(frame["overlay/shown"][1][:3, 3], (0.3, 0.0, 0.06), atol=1e-6)
        viewer.on_turn({"action": {"kind": "none"}})
        assert viewer.frame()["overlay/question"][0][0].text == "Robot stays quiet."
        viewer.on_scene(None)
        assert not any(node.startswith("overlay/") for node in viewer.frame())
    finally:
        viewer.close()


def test_a_viewer_without_panels_highlights_but_leaves_the_words_to_the_page(bare):
    bare.three_objects()
    viewer = Viewer(bare, live=False, panels=False)
    try:
        viewer.on_scene(None)
        viewer.on_question(SimpleNamespace(kind="label", object_index=1, concept=None), "What is this (object 2)?")
        viewer.on_answer(SimpleNamespace(kind="label"), SimpleNamespace(raw="a fruit", kind="answer", value="fruit"))
        frame = viewer.frame()
        assert "overlay/asked" in frame and any(node.startswith("labels/") for node in frame)
        assert "overlay/question" not in frame and "overlay/answer" not in frame
    finally:
        viewer.close()


def test_live_fps_bounds_the_frames_a_moving_arm_sends(bare):
    viewer = Viewer(bare, live_fps=5.0)
    try:
        published = viewer.thread.frames_published
        started = time.perf_counter()
        while time.perf_counter() - started < 1.0:  # a second of stepping as fast as the machine goes
            p.stepSimulation(physicsClientId=bare.client)
        assert 3 <= viewer.thread.frames_published - published <= 6  # at most 5 a second, not one a step
    finally:
        viewer.close()


def _page_commands(html: str) -> list[dict]:
    blobs = re.findall(r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)', html)
    return [umsgpack.unpackb(base64.b64decode(blob)) for blob in blobs]


def test_export_writes_one_page_with_the_animation_and_no_server(bare, tmp_path):
    box, _, _ = bare.three_objects()
    viewer = Viewer(bare, live=False, record=True, fps=20)
    try:
        viewer.on_scene(None)
        p.resetBaseVelocity(box, [0.5, 0, 0], physicsClientId=bare.client)
        for _ in range(240):
            p.stepSimulation(physicsClientId=bare.client)
        viewer.on_question({"kind": "label", "object": 1}, "What is this (object 1)?")
        final = np.asarray(p.getBasePositionAndOrientation(box, physicsClientId=bare.client)[0])
        written = viewer.export_html(tmp_path / "episode.html", title="a <test>")
    finally:
        viewer.close()
    html = (tmp_path / "episode.html").read_text()
    assert written["bytes"] == len(html.encode()) and "<title>a &lt;test&gt;</title>" in html
    assert "viewer.connect" not in html  # the page needs no server
    commands = _page_commands(html)
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    clips = {a["path"]: a["clip"] for a in animation["animations"]}
    travel, last = {}, {}
    for path, clip in clips.items():
        for track in clip["tracks"]:
            if path.startswith("/meshcat/world/objects/") and track["name"] == ".position":
                positions = np.frombuffer(track["values"].data, dtype=np.float32).reshape(-1, 3)
                travel[path] = float(positions[-1, 0] - positions[0, 0])
                last[path] = positions[-1]
    pushed = max(travel, key=travel.get)
    assert travel[pushed] > 0.03, "the pushed box slid along x until friction stopped it"
    assert np.allclose(last[pushed], final, atol=1e-4), "the last key is where PyBullet left it"
    assert sorted(abs(t) for t in travel.values())[:-1] < [0.01, 0.01], "the others only settled"
    asked = [path for path, clip in clips.items() if path.startswith("/meshcat/world/overlay/asked")]
    (visible,) = [t for t in clips[asked[0]]["tracks"] if t["name"] == ".visible"]
    assert visible["values"][0] is False and visible["values"][-1] is True  # appears when the question is asked
    assert written["seconds"] > 1.0 and viewer.recording.samples > 20
