// The teaching page: shows the session's state and sends answers; the server checks every message.
"use strict";

const TOKEN = document.body.dataset.token;
const WS_BASE = (location.protocol === "https:" ? "wss://" : "ws://") + location.host;
const $ = (id) => document.getElementById(id);
let socket = null;
let question = null;     // the open question, as the server described it
let waiting = false;     // whether the robot waits for an answer now
let shownAt = 0;         // when this page first showed the open question (for page_ms)
let ended = false;
let viewer = null;       // the meshcat 3D view, when its script loaded
let objectNodes = {};    // meshcat node name -> object number (for clicks in the 3D view)
let view = 0;            // which 3D view is connected (0: none)

function status(text) { $("status").textContent = text; }

function connect() {
  socket = new WebSocket(`${WS_BASE}/ws?token=${encodeURIComponent(TOKEN)}`);
  socket.onopen = () => status("Connected");
  socket.onmessage = (event) => handle(JSON.parse(event.data));
  socket.onclose = () => {
    if (ended) { status("The session is over."); return; }
    status("Connection lost: reconnecting…");
    setTimeout(connect, 1000);
  };
}

function send(message) {
  if (!question || !waiting || !socket || socket.readyState !== WebSocket.OPEN) { return; }
  message.question = question.id;
  message.page_ms = Math.round(performance.now() - shownAt);
  $("refused").textContent = "";
  setWaiting(false);
  socket.send(JSON.stringify(message));
}

function handle(message) {
  if (message.type === "state") {
    $("conversation").replaceChildren();
    message.conversation.forEach(addLine);
    if (message.question) { showQuestion(message.question); } else { clearQuestion(); }
    if (message.screen) { showScreen(message.screen); }
    if (message.view !== view) { start3d(message.view); }
    setWaiting(message.waiting);
    if (message.ended) { showEnded(message.end_text); }
    objectNodes = message.nodes || {};
  } else if (message.type === "line") {
    addLine(message);
  } else if (message.type === "question") {
    showQuestion(message.question);
  } else if (message.type === "waiting") {
    if (question && message.question === question.id) { setWaiting(true); }
  } else if (message.type === "budget") {  // an undo gave budget back
    if (question && message.question === question.id) { question.budget_left = message.budget_left; showMeta(question, true); }
  } else if (message.type === "refused") {
    $("refused").textContent = `Not taken: ${message.reason}`;
    setWaiting(true);
  } else if (message.type === "screen") {
    showScreen(message.screen);
  } else if (message.type === "ended") {
    showEnded(message.text);
  } else if (message.type === "view") {
    start3d(message.view);
  } else if (message.type === "nodes") {
    objectNodes = message.nodes;
  } else if (message.type === "clear") {  // a study's next session: its conversation starts empty
    $("conversation").replaceChildren();
  }
}

function addLine(entry) {
  const item = document.createElement("li");
  item.className = entry.who;
  const who = {robot: "Robot: ", teacher: "You: ", scripted: "Teacher: "};  // scripted: demo's teacher
  item.textContent = (who[entry.who] || "") + entry.text;
  $("conversation").appendChild(item);
  item.scrollIntoView({block: "nearest"});
}

function button(label, key, onClick, primary) {
  const element = document.createElement("button");
  element.type = "button";
  if (key) {
    const hint = document.createElement("kbd");
    hint.textContent = key;
    element.append(hint, " ");
    element.dataset.key = key;
  }
  element.append(label);
  if (primary) { element.className = "primary"; }
  element.addEventListener("click", onClick);
  return element;
}

function showQuestion(asked) {
  const fresh = !question || question.id !== asked.id;
  question = asked;
  if (fresh) { shownAt = performance.now(); }
  $("screen").hidden = true;
  $("ask").hidden = false;
  if (document.body.classList.contains("idle")) {  // the kitchen and the answer controls are for questions
    document.body.classList.remove("idle");
    if (viewer) { viewer.set_3d_pane_size(); viewer.needs_render = true; }  // sized while hidden: 0 by 0
  }
  $("typed").hidden = $("commands").hidden = Boolean(asked.watch);  // a demo: watched, not answered
  showMeta(asked);
  if (asked.seconds_left !== null) { countdown(asked.id, asked.seconds_left); }
  $("question-text").textContent = asked.text;
  const answers = $("answers");
  answers.replaceChildren();
  if (asked.watch) {
    status(`Turn ${asked.turn}: the scripted teacher answers`);
  } else if (asked.expects === "label") {
    asked.concepts.forEach((concept, i) => {
      answers.appendChild(button(concept, i < 9 ? String(i + 1) : "", () => send({type: "concept", concept}), true));
    });
    answers.appendChild(button("don't know", "d", () => send({type: "command", command: "don't know"})));
  } else if (asked.expects === "demo") {
    const hint = document.createElement("p");
    hint.textContent = "Click the object in the camera picture or the 3D view, or:";
    answers.appendChild(hint);
    answers.appendChild(button("none here", "n", () => send({type: "command", command: "none"}), true));
    answers.appendChild(button("don't know", "d", () => send({type: "command", command: "don't know"})));
    const numbers = document.createElement("div");
    numbers.id = "object-numbers";
    numbers.setAttribute("aria-label", "Or choose the object by its number");
    for (let n = 1; n <= asked.objects; n++) {
      const pick = button(String(n), "", () => send({type: "object", object: n}));
      pick.setAttribute("aria-label", `object ${n}`);
      numbers.appendChild(pick);
    }
    answers.appendChild(numbers);
  } else if (asked.expects === "feature") {
    answers.appendChild(featureTree(asked.features));
    answers.appendChild(button("use these", "", () => sendFeatures("use"), true));
    answers.appendChild(button("ignore these", "", () => sendFeatures("ignore")));
  }
  if (asked.picture) {
    $("picture").src = `/picture/${asked.id}?token=${encodeURIComponent(TOKEN)}`;
    $("picture").hidden = false;
    $("picture-caption").textContent = asked.expects === "demo"
      ? "Camera picture: click the object you mean." : "Camera picture (the robot's view, numbered).";
  } else if (!asked.watch) {  // no picture of its own: an earlier question's ring would point at nothing asked now
    $("picture").hidden = true;
    $("picture").removeAttribute("src");
    $("picture-caption").textContent = "This question is not about one object.";
  }
}

function showMeta(asked, again) {
  // the turn, the budget left (unless hidden) and the seconds left; shown ``again`` (an undo), the countdown goes on
  const counting = again ? $("countdown") : null;
  let meta = `Turn ${asked.turn}` + (asked.turns ? ` of ${asked.turns}` : "")
    + (asked.budget_left === null ? "" : ` · budget left ${asked.budget_left}`);
  const seconds = counting ? counting.textContent : asked.seconds_left === null ? null : Math.round(asked.seconds_left);
  if (seconds !== null) { meta += ` · <span id="countdown">${seconds}</span> s to answer`; }
  $("meta").innerHTML = meta;
}

function clearQuestion() {
  question = null;
  $("question-text").textContent = "";
  $("answers").replaceChildren();
  $("meta").textContent = "";
}

function setWaiting(on) {
  if (waiting && !on) { busySince = performance.now(); }
  if (!on) { $("confirm").hidden = true; }  // no question open: nothing to stop from here
  const asking = !waiting && Boolean(on) && !ended;
  waiting = Boolean(on) && !ended;
  if (asking && question) { afterPaint(question.id); }
  document.querySelectorAll("#ask button, #ask input").forEach((element) => { element.disabled = !waiting; });
  if (waiting && question) { status(`Turn ${question.turn}: your answer, please`); }
  else if (!ended && !$("screen").hidden) { status($("screen").dataset.title); }  // a study screen says what it is
  else if (!ended) { status("The robot is busy…"); }
}

function showEnded(text) {
  ended = true;
  document.body.classList.add("idle");  // no kitchen, no answer controls: nothing is asked any more
  setWaiting(false);
  question = null;
  $("screen").hidden = true;
  $("ask").hidden = false;
  $("question-text").textContent = text || "The session is over. Thank you!";
  $("answers").replaceChildren();
  status("The session is over.");
}

function countdown(id, seconds) {
  const end = performance.now() + seconds * 1000;
  const tick = () => {
    const element = $("countdown");
    if (!element || !question || question.id !== id) { return; }
    element.textContent = Math.max(0, Math.round((end - performance.now()) / 1000));
    if (performance.now() < end) { setTimeout(tick, 250); }
  };
  tick();
}

// -- answering by pointing: the camera picture and the 3D view ----------------------------------------
$("picture").addEventListener("click", (event) => {
  if (!question || question.expects !== "demo") { return; }
  const box = event.target.getBoundingClientRect();
  send({type: "click", x: (event.clientX - box.left) / box.width, y: (event.clientY - box.top) / box.height});
});

function start3d(which) {
  // (re)connect the 3D view: a study's next session brings another kitchen's mirror
  view = which;
  $("view3d").replaceChildren();
  viewer = null;
  if (!which || typeof MeshCat === "undefined") { return; }
  viewer = new MeshCat.Viewer($("view3d"), true, renderer3d());
  if (viewer.gui) { viewer.gui.close(); }
  fit3d();
  throttle3d();
  viewer.connect(`${WS_BASE}/meshcat-ws?token=${encodeURIComponent(TOKEN)}&view=${which}`);
}

function softwareWebGL() {
  // whether WebGL is drawn by the CPU (SwiftShader, llvmpipe: a browser without a GPU), where every frame of the
  // arm's 100,000 triangles costs a core a fifth of a second
  const canvas = document.createElement("canvas");
  const gl = canvas.getContext("webgl");
  if (!gl) { return false; }
  const info = gl.getExtension("WEBGL_debug_renderer_info");
  const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : "";
  const lose = gl.getExtension("WEBGL_lose_context");
  if (lose) { lose.loseContext(); }
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

function renderer3d() {
  // meshcat's own renderer, but without multisampling when the CPU draws (it more than doubles a frame's cost)
  software3d = softwareWebGL();
  const renderer = new MeshCat.THREE.WebGLRenderer({antialias: !software3d, alpha: true});
  renderer.shadowMap.enabled = true;
  renderer.shadowMap.type = MeshCat.THREE.PCFSoftShadowMap;
  $("view3d").appendChild(renderer.domElement);
  return renderer;
}

// A click in the 3D view: meshcat's orbit controls take the pointer from the canvas, so the press and the
// release are watched on the document; one in the same place on the canvas picks the object under it.
let pressed = null;
function onCanvas(event) {
  if (!viewer) { return false; }
  const box = viewer.renderer.domElement.getBoundingClientRect();
  return event.clientX >= box.left && event.clientX <= box.right && event.clientY >= box.top && event.clientY <= box.bottom;
}
document.addEventListener("pointerdown", (event) => { pressed = onCanvas(event) ? [event.clientX, event.clientY] : null; }, true);
document.addEventListener("pointerup", (event) => {
  const still = pressed && onCanvas(event) && Math.hypot(event.clientX - pressed[0], event.clientY - pressed[1]) < 5;
  pressed = null;
  if (!still || !question || question.expects !== "demo") { return; }
  const number = objectAt(event);
  if (number !== null) { send({type: "pick", object: number}); }
}, true);

const BUSY_3D_FPS = 3;     // while the robot works, with a GPU (and in a watched demo): a few frames a second
const SOFTWARE_BUSY_MS = 1000;  // without one: at most one frame a second, and none in the first second
let software3d = false;    // whether the CPU draws the 3D view (softwareWebGL)
let busySince = 0;         // when the robot began working (the answer was sent)
let drawn3d = null;        // the last question the 3D view was drawn for while it waited (its id)
let painted = null;        // the last question whose words and buttons are on the screen (its id)
let paintedAt = 0;         // when that was (performance.now(); scripts/bench_web.py reads it)

function afterPaint(id) {
  // note when the question waiting for its answer has been painted: after the next frame's rendering (a
  // callback before it, a task after it); the 3D view, drawn in software, waits for that (throttle3d)
  requestAnimationFrame(() => setTimeout(() => {
    painted = id;
    paintedAt = performance.now();
    if (viewer) { viewer.needs_render = true; }
  }, 0));
}

function throttle3d() {
  // meshcat renders on the next animation frame after every change. While the robot is busy (pointing, deciding)
  // the page draws at most BUSY_3D_FPS frames a second. Drawn by the CPU (no GPU) a frame takes a core for a
  // tenth to a fifth of a second, which the robot needs between an answer and the next question: so there,
  // while the robot works for an answer, the view is drawn at most once a second and not in the first second
  // (most turns end sooner). When the question arrives, the view is drawn as soon as the question's words are
  // on the screen (the arm pointing, the highlight): a frame drawn in software holds the page until it is done
  // (Chromium reads it back for its software compositor), so drawn first it would hold the question back by as
  // long. While the question waits the view is drawn freely (orbiting it).
  const render = viewer.render.bind(viewer);
  let last = 0;
  viewer.render = () => {
    const now = performance.now();
    if (software3d && waiting && question && painted !== question.id) {
      viewer.needs_render = true;
      return;
    }
    const held = software3d && !(question && question.watch)  // a watched demo has no answers to wait for
      ? now - Math.max(last, busySince) < SOFTWARE_BUSY_MS : now - last < 1000 / BUSY_3D_FPS;
    if (!waiting && !ended && held) {
      viewer.needs_render = true;
      return;
    }
    last = now;
    if (software3d) { diffuseOnly(viewer.scene, MeshCat.THREE); }
    render();
    if (waiting && question) { drawn3d = question.id; }
  };
}

function fit3d() {
  // meshcat sizes its canvas to the window's height whenever it resizes; here it always takes the page's box
  if (!viewer) { return; }
  const resize = viewer.set_3d_pane_size.bind(viewer);
  viewer.set_3d_pane_size = () => resize($("view3d").clientWidth, $("view3d").clientHeight);
  viewer.set_3d_pane_size();
}

function objectAt(event) {
  // the object under the cursor: the first hit whose node (or an ancestor's) is a scene object's
  const box = viewer.renderer.domElement.getBoundingClientRect();
  const pointer = new MeshCat.THREE.Vector2(((event.clientX - box.left) / box.width) * 2 - 1,
                                             -((event.clientY - box.top) / box.height) * 2 + 1);
  const ray = new MeshCat.THREE.Raycaster();
  ray.setFromCamera(pointer, viewer.camera);
  for (const hit of ray.intersectObjects(viewer.scene.children, true)) {
    for (let node = hit.object; node; node = node.parent) {
      if (node.name in objectNodes) { return objectNodes[node.name]; }
    }
  }
  return null;
}

// -- quitting has to be meant: "Stop this session?", with "Go on" the default ----------------------------
function confirmOpen() { return !$("confirm").hidden; }

function askToQuit() {
  if (!question || !waiting) { return; }
  $("confirm").hidden = false;
  $("confirm-go-on").disabled = $("confirm-stop").disabled = false;
  $("confirm-go-on").focus();  // Enter, Space or Escape go on; only "y" (or the button) stops
}

function closeConfirm(stop) {
  if (!confirmOpen()) { return; }
  $("confirm").hidden = true;
  if (stop) { send({type: "command", command: "quit"}); }
}

$("confirm-go-on").addEventListener("click", () => closeConfirm(false));
$("confirm-stop").addEventListener("click", () => closeConfirm(true));

document.addEventListener("keydown", (event) => {
  if (event.ctrlKey || event.altKey || event.metaKey) { return; }
  if (confirmOpen()) {  // while the page asks whether to stop, only its answers count
    if (event.key === "y" || event.key === "Y") { event.preventDefault(); closeConfirm(true); }
    else if (["Escape", "n", "N", "g", "G"].includes(event.key)) { event.preventDefault(); closeConfirm(false); }
    else if (event.key !== "Enter" && event.key !== " " && event.key !== "Tab") { event.preventDefault(); }
    return;
  }
  if (event.target.tagName === "INPUT" || event.target.tagName === "TEXTAREA") { return; }
  const target = document.querySelector(`#ask button[data-key="${CSS.escape(event.key)}"]`);
  if (target && !target.disabled) { event.preventDefault(); target.click(); }
});

$("commands").addEventListener("click", (event) => {
  const command = event.target.closest("button")?.dataset.command;
  if (command === "quit") { askToQuit(); } else if (command) { send({type: "command", command}); }
});

$("typed").addEventListener("submit", (event) => {
  event.preventDefault();
  const text = $("line").value;
  if (!text.trim()) { return; }
  $("line").value = "";
  send({type: "typed", text});
});

connect();
