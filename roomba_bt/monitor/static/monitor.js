// roomba-bt monitor page: no framework, no external assets (the laptop may be offline).
// Live: a WebSocket brings at most ~20 updates a second. Timeline: GET /api/state?tick=T.
// Controls: POST /api/control, answered 202 or with an HTTP error the page shows.
// A dropped socket (Wi-Fi, a laptop's sleep, a proxy) marks the page stale and turns the
// controls off; it connects again with backoff (1, 2, 4 ... 10 s) and fetches the run afresh.
// Each run has an id (the hello's header.run): a page that connects again and finds another
// run served on its port (its own was killed, a new one started there, perhaps on another
// robot) does not take it: it says so, keeps its controls off and stops connecting. Every
// control carries the id the page was loaded for; the server refuses one for another run.
// A silent link (packets lost, the socket not closed: a train's tunnel) is no drop: the run
// speaks at least once a second, so after SILENT_MS without a word the page says so and turns
// off what sets the robot going; each control echoes the server's stamp of the last update
// ("seen"), and the server refuses a resume, step or force from a view too far behind.
"use strict";

const SYMBOL = {
  sequence_with_memory: "{-}", sequence_without_memory: "[-]",
  selector_with_memory: "{o}", selector_without_memory: "[o]",
  parallel: "/_/", decorator: "-^-", behaviour: "-->",
};
const STATUS_SYMBOL = { S: "✓", F: "✕", R: "*", I: "-" };
const STATUS_NAME = { S: "SUCCESS", F: "FAILURE", R: "RUNNING", I: "INVALID" };
const SLOT = 0.015;

const token = new URLSearchParams(location.search).get("token");
const $ = (id) => document.getElementById(id);
// Resume's title as the page has it, for a run that is not held at its mission's end
const RESUME_TITLE = $("resume").title;
if (token) {
  // the server has set its HttpOnly cookie with this page (Path=/), which authorises a reload
  // and every request after it: the token leaves the address bar (a screen share, a
  // screenshot, the history), and the page keeps it in memory for its socket
  const clean = new URL(location.href);
  clean.searchParams.delete("token");
  history.replaceState(null, "", clean.pathname + clean.search + clean.hash);
}

const view = {
  header: null, tree: [], rows: [], shown: "", collapsed: new Set(),
  live: true, liveState: null, session: { paused: false, breakpoints: {}, forced: {} },
  events: [], path: { odometry: [], truth: [] }, pathLive: { odometry: [], truth: [] },
  // the state the panels show (the packets panel, opened, shows it at once)
  shownState: null,
  world: null, fontSize: 13, follow: true, shownTick: 0, window: [0, 0], playing: null, menuNode: null, menuFrom: null,
  finished: null, ended: false,
  // why a record's view has no end to show (header.no_end: a killed run's record), or null
  noEnd: null,
  // what the run's safe stop left the robot in, when the state shown is after it (state.ended)
  shownEnded: null,
  // the run this page watches (its first hello's header.run.id), and another run found
  // served here since (its header.run), which the page does not take
  runId: null, otherRun: null,
  // the socket (the page's one: null before the first), connected, when it dropped, the next
  // try's delay (ms) and its timer
  socket: null, connected: false, droppedAt: null, retryMs: 1000, retryTimer: null, retryAt: 0,
  // when the socket last brought a message (this browser's clock), and the server's stamp of
  // it (its "sent", echoed as a control's "seen": the server compares it with its own clock)
  heardAt: null, sent: null,
};
const RETRY_MAX_MS = 10000;
const GOING_AWAY = 1001;  // the server's close when the run ended (or the monitor stopped)
const SILENT_MS = 2000;  // the run speaks every second at least: silent longer, the link is
const CONTROL_TIMEOUT_MS = 5000;  // a control unanswered this long is said not confirmed
const MOTION = new Set(["resume", "step", "force"]);  // what sets the robot going
// the page's keys, the terminal's four (each button's title names its key; q was not one,
// though Stop's title said "key q")
const PAGE_KEYS = { p: "pause", r: "resume", n: "step", q: "stop" };

// whole seconds the open socket has brought nothing, when over SILENT_MS; 0 otherwise
function silentSeconds() {
  if (!view.connected || view.heardAt === null) return 0;
  const quiet = Date.now() - view.heardAt;
  return quiet > SILENT_MS ? Math.floor(quiet / 1000) : 0;
}

function headers() {
  const h = { "Content-Type": "application/json" };
  if (token) h["X-Monitor-Token"] = token;
  return h;
}

// a control the page sent whose answer has not come: its button says so ("Pausing…") and
// takes no second press until the run's server accepts or refuses it (which the alert says)
const PENDING_LABELS = { pause: "Pausing…", resume: "Resuming…", step: "Stepping…", stop: "Stopping…" };
const pending = new Set();

async function control(action, node, value) {
  const button = action in PENDING_LABELS ? action : null;
  if (button) { pending.add(button); updateControls(); }
  try {
    return await sendControl(action, node, value);
  } finally {
    if (button) { pending.delete(button); updateControls(); }
  }
}

async function sendControl(action, node, value) {
  const body = { action, run: view.runId, seen: view.sent };
  if (node !== undefined) body.node = node;
  if (value !== undefined) body.value = value;
  let reply;
  const abort = new AbortController(), timer = setTimeout(() => abort.abort(), CONTROL_TIMEOUT_MS);
  try {
    reply = await fetch("api/control", { method: "POST", headers: headers(), body: JSON.stringify(body), signal: abort.signal });
  } catch (e) {
    // the request never reached the run, or sits in a stalled network: say so where the
    // operator looks (it failed silently; a resume sat 60 s in a stall, then set the robot going)
    showAlert(abort.signal.aborted
      ? `${action} NOT confirmed: no answer from the run in ${CONTROL_TIMEOUT_MS / 1000} s; it may still reach it`
        + (MOTION.has(action) ? ` (a late ${action} is refused there)` : "")
      : `${action} NOT sent: no connection to the run (${e.message}); the robot does what it did`);
    return false;
  } finally {
    clearTimeout(timer);
  }
  if (!reply.ok) {
    let text = `${reply.status}`;
    try { text += ": " + (await reply.json()).error; } catch (e) { /* not JSON */ }
    showAlert(`${action} refused (${text})`);
  } else showAlert("");
  return reply.ok;
}

function showBanner(text, error) {
  const b = $("banner");
  if (!text) { b.hidden = true; return; }
  b.hidden = false; b.textContent = text; b.classList.toggle("error", Boolean(error));
}

// a control that failed: red, above the state's banner (which updates 20 times a second and
// used to overwrite it), until the next control goes through or the operator closes it
function showAlert(text) {
  $("alert").hidden = !text;
  $("alert-text").textContent = text || "";
}

// ------------------------------------------------------------------ the tree
function buildTree(nodes) {
  // a menu opened on the old tree names a node by its index, which is another node of this
  // one (a reload, perhaps while the socket was down): closed, so break and force cannot
  // reach the wrong node
  closeMenu();
  view.tree = nodes; view.shown = ""; view.rows = [];
  const inner = $("tree-inner");
  inner.textContent = "";
  for (const n of nodes) {
    const row = document.createElement("div");
    row.className = "node";
    row.dataset.node = n.i; row.dataset.name = n.name; row.dataset.status = "I"; row.dataset.depth = n.depth;
    row.style.paddingLeft = `calc(${n.depth} * var(--indent))`;  // narrower on a phone (CSS)
    const toggle = document.createElement("span");
    toggle.className = "toggle";
    toggle.textContent = n.children.length ? "▾" : "";
    toggle.addEventListener("click", (ev) => { ev.stopPropagation(); toggleNode(n.i); });
    if (n.children.length) {
      // reached by Tab and worked by Enter or Space, its state said (aria-expanded): the
      // subtrees folded by a mouse only
      toggle.tabIndex = 0; toggle.setAttribute("role", "button");
      toggle.setAttribute("aria-label", `${n.label || n.name}: its subtree`);
      toggle.addEventListener("keydown", (ev) => {
        if (ev.key === "Enter" || ev.key === " ") { ev.preventDefault(); ev.stopPropagation(); toggleNode(n.i); }
      });
    }
    const kind = document.createElement("span"); kind.className = "kind"; kind.textContent = SYMBOL[n.kind] || "-->";
    const name = document.createElement("span"); name.className = "name"; name.textContent = n.label || n.name;
    name.title = name.textContent;  // the whole of a name cut short to keep its status in view
    // reached by Tab, its menu opened by Enter or Space: the breakpoints and forces were a
    // mouse's or a finger's only
    name.tabIndex = 0; name.setAttribute("role", "button"); name.setAttribute("aria-haspopup", "true");
    name.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter" || ev.key === " ") { ev.preventDefault(); openMenu(n.i, ev, name); }
    });
    const st = document.createElement("span"); st.className = "st st-I"; st.textContent = "[-]";
    const marks = document.createElement("span"); marks.className = "marks";
    const reason = document.createElement("span"); reason.className = "reason";
    row.append(toggle, kind, name, st, marks, reason);
    row.addEventListener("click", (ev) => openMenu(n.i, ev));
    inner.appendChild(row);
    view.rows.push({ row, st, reason, marks, toggle, name });
  }
  applyCollapse();
  fitTree();
}

function descendants(i, out) {
  for (const c of view.tree[i].children) { out.push(c); descendants(c, out); }
  return out;
}

function toggleNode(i) {
  if (view.collapsed.has(i)) view.collapsed.delete(i); else view.collapsed.add(i);
  applyCollapse();
}

function applyCollapse() {
  const hidden = new Set();
  for (const i of view.collapsed) if (view.tree[i]) for (const d of descendants(i, [])) hidden.add(d);
  view.rows.forEach((r, i) => {
    r.row.hidden = hidden.has(i);
    if (view.tree[i].children.length) {
      r.toggle.textContent = view.collapsed.has(i) ? "▸" : "▾";
      r.toggle.setAttribute("aria-expanded", String(!view.collapsed.has(i)));
      r.toggle.title = view.collapsed.has(i) ? "expand (Enter)" : "collapse (Enter)";
    }
  });
  followRunning();
}

// the smallest text "fit" and a window's resize go to: a big tree (the clean mission's) fitted
// whole was 6 px, unreadable; it scrolls instead, the running node kept in view (followRunning)
const MIN_FONT_PX = 12;
function fitTree() {
  const box = $("tree"), inner = $("tree-inner");
  let size = 16;
  inner.style.fontSize = size + "px";
  while (size > MIN_FONT_PX && (inner.scrollHeight > box.clientHeight || inner.scrollWidth > box.clientWidth)) {
    size -= 0.5; inner.style.fontSize = size + "px";
  }
  view.fontSize = size;
  followRunning();
}

function zoom(by) { view.fontSize = Math.max(5, Math.min(28, view.fontSize + by)); $("tree-inner").style.fontSize = view.fontSize + "px"; followRunning(); }

// as Groot follows a running tree: the deepest RUNNING node shown (the leaf at work) is
// scrolled into the tree's view when it is out of it, a third down and its name from the
// left; "follow" turns it off for reading elsewhere in the tree
function followRunning() {
  if (!view.follow) return;
  let deepest = null;
  view.rows.forEach((r, i) => {
    if (r.row.dataset.status === "R" && !r.row.hidden
        && (deepest === null || view.tree[i].depth > view.tree[deepest].depth)) deepest = i;
  });
  if (deepest === null) return;
  const box = $("tree"), frame = shownPart(box);
  const at = view.rows[deepest].row.getBoundingClientRect();
  // the tree scrolled off the page (a phone's reader further down): nothing to keep in view
  if (frame.bottom - frame.top < 2 * at.height) return;
  const name = view.rows[deepest].name.getBoundingClientRect();
  if (at.top < frame.top || at.bottom > frame.bottom) {
    box.scrollTop += at.top - frame.top - Math.min(box.clientHeight, frame.bottom - frame.top) / 3;
  }
  if (name.left < frame.left || name.left + 40 > frame.right) box.scrollLeft += name.left - frame.left - 40;
}
// the part of an element's box the reader sees: on a phone the page scrolls under the stuck
// top (the header, its controls and status), which covered the running node followed in the
// tree's box; the window's bottom cuts it too
function shownPart(element) {
  const box = element.getBoundingClientRect();
  return { top: Math.max(box.top, $("top").getBoundingClientRect().bottom),
    bottom: Math.min(box.bottom, window.innerHeight), left: box.left, right: box.right };
}
function setFollow(on) {
  view.follow = on;
  $("follow").classList.toggle("active", on);
  $("follow").setAttribute("aria-pressed", String(on));
  followRunning();
}

function renderStatuses(state) {
  const statuses = state.statuses || "";
  const changed = new Set(state.changed || []);
  const reasons = state.reasons || {};
  const bps = view.session.breakpoints || {}, forced = view.session.forced || {};
  view.rows.forEach((r, i) => {
    const s = statuses[i] || "I";
    if (r.row.dataset.status !== s || view.shown === "") {
      r.row.dataset.status = s;
      r.st.className = "st st-" + s;
      r.st.textContent = "[" + STATUS_SYMBOL[s] + "]";
      r.row.title = STATUS_NAME[s];
    }
    r.row.classList.toggle("running", s === "R");
    if (changed.has(i)) { r.row.classList.remove("flash"); void r.row.offsetWidth; r.row.classList.add("flash"); }
    const why = s === "F" && reasons[String(i)] ? "-- " + reasons[String(i)] : "";
    if (r.reason.textContent !== why) r.reason.textContent = why;
    let marks = "";
    if (bps[String(i)]) marks += "●";
    if (forced[String(i)]) marks += "⚑" + (forced[String(i)] === "success" ? "✓" : "✕");
    if (r.marks.textContent !== marks) { r.marks.textContent = marks; r.marks.className = "marks " + (bps[String(i)] ? "bp" : "forced-mark"); }
  });
  view.shown = statuses;
  followRunning();
}

// ------------------------------------------------------------------ menu (breakpoints, force)
// ``from``: the node's name it was opened from with a key (Enter, Space): the menu is put
// under it and takes the focus, which goes back to the name when the menu closes
function openMenu(i, ev, from) {
  const menu = $("node-menu"), n = view.tree[i];
  view.menuNode = i; view.menuFrom = from || null;
  $("node-menu-title").textContent = (n.label || n.name) + (n.condition ? " (condition)" : "");
  const reason = (view.liveState && view.liveState.reasons || {})[String(i)];
  $("node-menu-reason").textContent = reason ? "failed: " + reason : "";
  menuState();
  $("force-row").hidden = !(n.condition && view.header && view.header.can_force);
  menu.hidden = false;
  const box = from ? from.getBoundingClientRect() : null;
  const x = box ? box.left : ev.clientX, y = box ? box.bottom : ev.clientY;
  menu.style.left = Math.min(x, window.innerWidth - 360) + "px";
  menu.style.top = Math.min(y + 8, window.innerHeight - 120) + "px";
  if (from) (menu.querySelector("button:not([disabled])") || menu).focus();
  ev.stopPropagation();
}
// why the node menu's buttons are off ("" if they are not): a menu of greyed buttons said
// nothing, and a class's projector (the view-only link) took it for broken
function menuOffBecause() {
  const h = view.header;
  if (view.otherRun) return "a different run is now served here: reload to watch it";
  // a record's player is "finished" from its start: that is not why
  if (h && h.source === "record") return "a recorded run: breakpoints and forces are for a live run";
  if (view.finished) return "the run has ended: nothing to break or force";
  if (!view.connected || !h) return "no connection to the run: breakpoints and forces are off";
  if (h.controls) return "";
  if (h.view_only) return "view only: breakpoints and forces are on the control link";
  return h.readonly ? "read-only (--monitor-readonly): no breakpoints or forces" : "no controls on this page";
}
// the node menu's buttons, and the line that says why they are off
function menuState() {
  const why = menuOffBecause(), line = $("node-menu-why");
  menuButtons(why === "");
  if (line.textContent !== why) line.textContent = why;
  line.hidden = why === "";
}
// the node menu's buttons on (``on``), its force off while the run is silent (it sets the
// robot going; a breakpoint holds it)
function menuButtons(on) {
  const silent = silentSeconds() > 0;
  for (const b of $("node-menu").querySelectorAll("button")) b.disabled = !on || (silent && "force" in b.dataset);
}
function closeMenu() {
  const menu = $("node-menu"), back = view.menuFrom, inside = menu.contains(document.activeElement);
  menu.hidden = true; view.menuNode = null; view.menuFrom = null;
  if (back && inside) back.focus();  // a keyboard's reader goes on from the node
}
// the menu's node, then the menu closed; nothing when it names no node (closed since)
function menuControl(action, value) {
  const node = view.menuNode;
  closeMenu();
  if (node !== null) control(action, node, value);
}
document.addEventListener("click", (ev) => { if (!$("node-menu").contains(ev.target)) closeMenu(); });
for (const b of document.querySelectorAll("[data-break]")) b.addEventListener("click", () => menuControl("break", b.dataset.break));
for (const b of document.querySelectorAll("[data-force]")) b.addEventListener("click", () => menuControl("force", b.dataset.force));

// ------------------------------------------------------------------ robot panel
const lamp = (on, label) => `<span class="lamp ${on ? "on" : ""}">${on ? label : "·"}</span> `;
const degrees = (rad) => {
  let d = Math.round(rad * 180 / Math.PI) % 360;
  if (d > 180) d -= 360; if (d <= -180) d += 360;
  return String(d === 0 ? 0 : d);  // never "-0"
};
function irText(ir) {
  if (!ir) return "—";
  const parts = [];
  if (ir.red_buoy) parts.push("red buoy"); if (ir.green_buoy) parts.push("green buoy");
  if (ir.force_field) parts.push("force field"); if (ir.virtual_wall) parts.push("virtual wall");
  return `${ir.code}${parts.length ? " (" + parts.join(", ") + ")" : ""}`;
}
// one motor as the standing Motors (138) / PWM Motors (144) command set it: "main brush ON
// inward", "side brush ON 40 % clockwise", "vacuum off"
function motorText(name, m) {
  const on = m.percent > 0;
  const power = on && m.percent !== 100 ? ` ${m.percent} %` : "";
  const way = on && m.direction ? ` ${m.direction}` : "";
  return `<span class="motor${on ? " motor-on" : ""}">${name} ${on ? "ON" : "off"}${power}${way}</span>`;
}
function motorRows(r, rows) {
  const m = r.motors;
  if (m) {
    const note = m.note ? ` <span class="note">(${esc(m.note)})</span>` : "";
    rows.push([`motors${m.command ? " (" + m.command + ")" : ""}`, `<span id="motors">${motorText("main brush", m.main_brush)} · `
      + `${motorText("side brush", m.side_brush)} · ${motorText("vacuum", m.vacuum)}${note}</span>`]);
  }
  const o = r.overcurrents;
  if (o) rows.push(["overcurrent (14)", `<span id="overcurrents">${lamp(o.main_brush, "main")}${lamp(o.side_brush, "side")}${lamp(o.left_wheel, "L")}${lamp(o.right_wheel, "R")}</span>`]);
  const c = r.brush_currents_ma;
  if (c) rows.push(["brush currents (56, 57)", `<span id="brush-currents">${c.main_brush !== undefined ? `main ${c.main_brush} mA ` : ""}${c.side_brush !== undefined ? `side ${c.side_brush} mA` : ""}</span>`]);
}
// the two poses are in two frames: odometry from where the robot started, the simulator's
// true pose in the room; unlabelled, (0.02, 0.00) beside (2.10, 0.93) read as 2 m of error
const TRUE_POSE_LABEL = "<span title=\"the simulator's: where it has the robot; odometry is "
  + "the robot's own reckoning, from where it started\">true pose (in the room)</span>";
function renderRobot(state) {
  const r = state.robot;
  const rows = [];
  if (!r) { setRows("robot", [["no frame yet", ""]]); return; }
  rows.push(["OI mode", `<b id="mode">${r.mode}</b>`]);
  if (r.bumps) rows.push(["bumps", `<span id="bumps">${lamp(r.bumps.left, "L")} ${lamp(r.bumps.right, "R")}</span>`]);
  if (r.wheel_drops) rows.push(["wheel drops", `${lamp(r.wheel_drops.left, "L")} ${lamp(r.wheel_drops.right, "R")}`]);
  if (r.cliffs) rows.push(["cliffs", `<span id="cliffs">${lamp(r.cliffs.left, "L")} ${lamp(r.cliffs.front_left, "FL")} ${lamp(r.cliffs.front_right, "FR")} ${lamp(r.cliffs.right, "R")}</span>`]);
  if (r.ir) rows.push(["IR omni / left / right", `<span id="ir">${irText(r.ir.omni)} / ${irText(r.ir.left)} / ${irText(r.ir.right)}</span>`]);
  if (r.light_bumper) {
    const lb = r.light_bumper, sig = r.light_bump_signals || [];
    rows.push(["light bumper", `${lamp(lb.left, "L")}${lamp(lb.front_left, "FL")}${lamp(lb.center_left, "CL")}${lamp(lb.center_right, "CR")}${lamp(lb.front_right, "FR")}${lamp(lb.right, "R")} ${sig.length ? "[" + sig.join(" ") + "]" : ""}`]);
  }
  if (r.battery_percent !== undefined) rows.push(["battery", `<span id="battery">${r.battery_percent.toFixed(1)} %</span>`]);
  if (r.charging !== undefined) rows.push(["charging", `<span id="charging">${r.charging}</span>${r.charging_sources && r.charging_sources.home_base ? " (home base)" : ""}`]);
  if (r.wheels) rows.push([`wheels (mm/s, ${r.wheels.source})`, `<span id="wheels">${r.wheels.left !== undefined ? `L ${r.wheels.left} R ${r.wheels.right}` : `v ${r.wheels.velocity} r ${r.wheels.radius}`}</span>`]);
  motorRows(r, rows);
  if (r.commands_per_s !== undefined) rows.push(["commands / refused per s", `<span id="rates">${r.commands_per_s} / ${r.refused_per_s}</span>`]);
  const o = r.odometry;
  rows.push(["odometry (from its start)", `(${(o.x / 1000).toFixed(2)}, ${(o.y / 1000).toFixed(2)}) m, ${degrees(o.theta)}°, ${(o.path / 1000).toFixed(2)} m driven`]);
  if (state.truth) rows.push([TRUE_POSE_LABEL, `(${(state.truth[0] / 1000).toFixed(2)}, ${(state.truth[1] / 1000).toFixed(2)}) m, ${degrees(state.truth[2])}°`]);
  if (r.frames_lost) rows.push(["frames lost", String(r.frames_lost)]);
  setRows("robot", rows);
}

// a table's rows ([label, HTML] each) set where they changed: rebuilt 20 times a second, a
// pose or a blackboard value could not be selected to copy. Another set of labels: rebuilt.
const tableRows = new Map();
function setRows(id, rows) {
  const table = $(id), before = tableRows.get(id);
  if (!before || before.length !== rows.length || before.some((row, j) => row[0] !== rows[j][0])) {
    table.innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join("");
  } else {
    rows.forEach(([, v], j) => { if (before[j][1] !== v) table.rows[j].cells[1].innerHTML = v; });
  }
  tableRows.set(id, rows);
}

function renderBlackboard(state) {
  const bb = state.blackboard || {};
  const keys = Object.keys(bb);
  setRows("blackboard", keys.length ? keys.map((k) => [esc(k), esc(bb[k])]) : [["(no keys)", ""]]);
}
// ------------------------------------------------------------------ streamed packets
// every packet of the run's stream request, raw, named by the OI packet table the header
// brings (header.packets: the name a mission's sensor: and a plugin read it by, its title
// and unit): a packet no row of the robot panel decodes (dirt detect, 15; wall signal, 27)
// is here. Made only while its panel is open (closed, an update costs nothing more), its
// rows again only when the frame's packets change, a value's cell only when it does.
const packets = { ids: null, cells: [] };
const packetValue = (value, unit) => (unit === "bits" ? `${value} = 0b${value.toString(2)}` : String(value));
function renderPackets(state) {
  const streamed = state.robot && state.robot.streamed;
  const count = streamed ? `(${streamed.ids.length})` : "";
  // after the run's end the robot panel shows what its safe stop left; no frame shows that
  const when = view.shownEnded ? ": the last frame, before the run's safe stop"
    : view.live ? "" : ` at tick ${state.tick}`;
  $("packets-title").textContent = count + when;
  if (!$("packets-panel").open) return;
  const rows = $("packets-rows");
  if (!streamed) { rows.innerHTML = "<tr><td colspan=\"4\">no frame yet</td></tr>"; packets.ids = null; return; }
  const names = view.header.packets, key = streamed.ids.join(" ");
  if (packets.ids !== key) {
    rows.innerHTML = streamed.ids.map((id) => `<tr data-packet="${id}"><td>${id}</td>`
      + `<td title="${esc(names[id].title)}">${esc(names[id].name)}</td><td></td><td>${esc(names[id].unit)}</td></tr>`).join("");
    packets.cells = Array.from(rows.querySelectorAll("td:nth-child(3)"));
    packets.ids = key;
  }
  streamed.values.forEach((value, j) => {
    const text = packetValue(value, names[streamed.ids[j]].unit);
    if (packets.cells[j].textContent !== text) packets.cells[j].textContent = text;
  });
}
$("packets-panel").addEventListener("toggle", () => { if (view.shownState) renderPackets(view.shownState); });

function esc(s) { return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]); }

// ------------------------------------------------------------------ events
function addEvents(events) {
  for (const e of events) view.events.push(e);
  if (view.events.length > 2000) view.events.splice(0, view.events.length - 2000);
  renderEvents();
}
// what the event list shows: its key (the tick it greys after, its first and last event),
// whether it is the live list, and its last event's seq
const shownEvents = { key: null, live: false, last: null };
function eventRow(e, t) {
  const li = document.createElement("li");
  li.className = `kind-${e.kind}${e.tick > t ? " future" : ""}`;
  li.dataset.seq = e.seq;
  li.innerHTML = `<span class="k">${e.time.toFixed(3)}s ${e.kind}</span> ${esc(e.text)}`;
  return li;
}
function renderEvents() {
  // greyed by the stream's tick, the timeline's own: mission time stands still while paused
  const list = $("events"), box = list.parentElement, t = view.live ? Infinity : view.shownTick;
  // rewound: the 400 around the tick shown (the newest 400 left a seek's events out)
  let end = view.events.length;
  if (!view.live) {
    let at = 0;
    while (at < view.events.length && view.events[at].tick <= t) at++;
    end = Math.min(view.events.length, Math.max(at + 100, 400));
  }
  const shown = view.events.slice(Math.max(0, end - 400), end);
  const firstSeq = shown.length ? shown[0].seq : null, lastSeq = shown.length ? shown[shown.length - 1].seq : null;
  const key = `${t} ${firstSeq} ${lastSeq}`;
  // nothing new: the list, where it is scrolled and a selection in it stay (it was rebuilt and
  // snapped to the bottom at every update, 20 times a second)
  if (key === shownEvents.key) return;
  const atBottom = box.scrollHeight - box.scrollTop - box.clientHeight < 24;
  if (view.live && shownEvents.live && shownEvents.last !== null && firstSeq !== null) {
    // live: the oldest gone from the log leave the top, the new ones come at the bottom
    while (list.firstElementChild && Number(list.firstElementChild.dataset.seq) < firstSeq) list.firstElementChild.remove();
    list.append(...shown.filter((e) => e.seq > shownEvents.last).map((e) => eventRow(e, t)));
  } else {
    list.replaceChildren(...shown.map((e) => eventRow(e, t)));
  }
  Object.assign(shownEvents, { key, live: view.live, last: lastSeq });
  // as a terminal does: at the bottom it stays there; scrolled up to read, it is left there
  if (view.live) { if (atBottom) box.scrollTop = box.scrollHeight; return; }
  // the list follows the seek: the last event at or before the tick shown, near the bottom
  const past = list.querySelectorAll("li:not(.future)");
  const last = past.length ? past[past.length - 1] : null;
  box.scrollTop = last ? Math.max(0, last.offsetTop + last.offsetHeight - box.clientHeight + 24) : 0;
}

// ------------------------------------------------------------------ path
function toWorld(p, start) {
  if (!start) return p;
  const c = Math.cos(start[2]), s = Math.sin(start[2]);
  return [start[0] + c * p[0] - s * p[1], start[1] + s * p[0] + c * p[1]];
}
function drawPath(state, path) {
  const canvas = $("path"), g = canvas.getContext("2d");
  g.clearRect(0, 0, canvas.width, canvas.height);
  const w = view.world, start = path.truthStart || null;
  const pts = [];
  if (w) { for (const room of w.rooms) pts.push(...room); for (const wall of w.walls) pts.push([wall[0], wall[1]], [wall[2], wall[3]]); }
  const odo = path.odometry.map((p) => toWorld(p, start));
  pts.push(...path.truth, ...odo);
  if (!pts.length) return;
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  for (const [x, y] of pts) { x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x); y1 = Math.max(y1, y); }
  const pad = 300; x0 -= pad; y0 -= pad; x1 += pad; y1 += pad;
  const k = Math.min(canvas.width / (x1 - x0), canvas.height / (y1 - y0));
  const X = (x) => (x - x0) * k, Y = (y) => canvas.height - (y - y0) * k;
  const poly = (points, fill, stroke) => {
    g.beginPath(); points.forEach(([x, y], j) => (j ? g.lineTo(X(x), Y(y)) : g.moveTo(X(x), Y(y)))); g.closePath();
    if (fill) { g.fillStyle = fill; g.fill(); } if (stroke) { g.strokeStyle = stroke; g.stroke(); }
  };
  const line = (a, b, c, d, stroke, width, dash) => {
    g.beginPath(); g.setLineDash(dash || []); g.strokeStyle = stroke; g.lineWidth = width;
    g.moveTo(X(a), Y(b)); g.lineTo(X(c), Y(d)); g.stroke(); g.setLineDash([]); g.lineWidth = 1;
  };
  if (w) {
    for (const room of w.rooms) poly(room, "#f4f4ee", "#222");
    for (const d of w.dirt) {  // on the floor, under the rest; its dirt-detect level (15) in its middle
      poly(d.area, "rgba(190,140,70,.35)", "rgba(120,80,30,.7)");
      const xs = d.area.map((p) => p[0]), ys = d.area.map((p) => p[1]);
      g.fillStyle = "#5a4020"; g.font = "10px sans-serif"; g.textAlign = "center"; g.textBaseline = "middle";
      g.fillText(String(d.level), X((Math.min(...xs) + Math.max(...xs)) / 2), Y((Math.min(...ys) + Math.max(...ys)) / 2));
    }
    for (const o of w.obstacles) poly(o, "#b8a88a", "#6b5a3a");
    for (const d of w.drops) poly(d, "rgba(40,40,40,.45)", "#000");
    for (const wall of w.walls) line(...wall, "#111", 2);
    for (const v of w.virtual_walls) line(...v, "orange", 2, [6, 4]);
    for (const l of w.lighthouses) line(l[2], l[3], l[4], l[5], "orange", 1, [2, 3]);
    if (w.dock) {
      const d = w.dock, r = d.range * k;
      const wedge = (range, colour) => {
        g.beginPath(); g.moveTo(X(d.x), Y(d.y));
        g.arc(X(d.x), Y(d.y), r, -(d.facing + range[1]), -(d.facing + range[0]));
        g.closePath(); g.fillStyle = colour; g.fill();
      };
      wedge(d.red, "rgba(255,0,0,.13)"); wedge(d.green, "rgba(0,160,0,.13)");
      g.beginPath(); g.setLineDash([3, 3]); g.strokeStyle = "#2a6fdb";
      g.arc(X(d.x), Y(d.y), d.force_field * k, 0, 2 * Math.PI); g.stroke(); g.setLineDash([]);
      line(...d.plate, "green", 5);
    }
  }
  const trace = (points, colour, width) => {
    if (points.length < 2) return;
    g.beginPath(); g.strokeStyle = colour; g.lineWidth = width; g.lineJoin = "round";
    points.forEach(([x, y], j) => (j ? g.lineTo(X(x), Y(y)) : g.moveTo(X(x), Y(y)))); g.stroke(); g.lineWidth = 1;
  };
  trace(path.truth, "rgba(0,0,0,.35)", 5); trace(odo, "#2a6fdb", 1.6);
  const robot = (x, y, th, colour, fill) => {
    g.beginPath(); g.arc(X(x), Y(y), Math.max(3, 170 * k), 0, 2 * Math.PI);
    if (fill) { g.fillStyle = fill; g.fill(); } g.strokeStyle = colour; g.stroke();
    line(x, y, x + 220 * Math.cos(th), y + 220 * Math.sin(th), colour, 2);
  };
  if (state.robot) {
    const o = state.robot.odometry, p = toWorld([o.x, o.y], start);
    robot(p[0], p[1], o.theta + (start ? start[2] : 0), "#2a6fdb", null);
  }
  if (state.truth) robot(state.truth[0], state.truth[1], state.truth[2], "#222", "rgba(120,120,120,.35)");
}

function setPath(path) {
  view.path = { odometry: path.odometry, truth: path.truth, truthStart: path.truthStart || view.pathLive.truthStart };
}
function appendLivePath(p) {
  const L = view.pathLive;
  L.odometry.push(...p.odometry); L.truth.push(...p.truth);
  if (L.odometry.length > 20000) L.odometry.splice(0, 5000);
  if (L.truth.length > 20000) L.truth.splice(0, 5000);
}

// ------------------------------------------------------------------ state
function render(state) {
  $("time").textContent = state.time.toFixed(3);
  $("tick").textContent = state.tick;
  view.shownTick = state.tick;
  view.shownEnded = state.ended || null;
  view.shownState = state;
  renderStatuses(state); renderRobot(state); renderPackets(state); renderBlackboard(state);
  drawPath(state, view.live ? view.pathLive : view.path);
  renderEvents();
  updateTimeline();
  robotTitle();
}

// "3 min 12 s": how long a pause has lasted, in the stream's ticks (they go on while paused)
function duration(seconds) {
  const s = Math.max(0, Math.round(seconds));
  if (s < 60) return `${s} s`;
  const m = Math.floor(s / 60);
  return m < 60 ? `${m} min ${s % 60} s` : `${Math.floor(m / 60)} h ${m % 60} min`;
}

function updateControls() {
  const h = view.header || {}, s = view.session;
  const c = Boolean(view.connected && h.controls && !view.finished && !view.otherRun);
  // silent: pause and stop still go (late, they are safe); what sets the robot going waits
  // for word from the run
  const silent = silentSeconds();
  // before the first hello nothing is known: the controls stay off (they looked usable)
  $("controls").hidden = view.header !== null && !h.controls;
  controlButton("pause", !c || s.paused);
  controlButton("resume", !c || silent > 0 || !s.paused);
  // held at the mission's end, a resume ends the run: its title said it went back to the mode
  setTitle("resume", s.held_end ? "end the run with the mission's outcome (key r)" : RESUME_TITLE);
  controlButton("step", !c || silent > 0 || !s.paused);
  controlButton("stop", !c);
  menuState();
  statusBar(s);
  document.body.classList.toggle("stale", silent > 0 || (!view.connected && !(view.finished && view.ended)));
  if (view.connected) setBadge(silent ? `no word from the run for ${silent} s` : "connected", !silent);
  if (view.otherRun) {
    const o = view.otherRun;
    showBanner(`a different run is now served here (${runLabel({ run: o })}): reload to watch it. `
      + `This page showed ${runLabel(view.header)}; `
      + "its controls are off", true);
  }
  else if (!view.connected && !view.ended) {
    const wait = Math.max(0, Math.ceil((view.retryAt - Date.now()) / 1000));
    const again = view.retryTimer ? (wait ? `connecting again in ${wait} s` : "connecting again now") : "connecting";
    if (view.droppedAt === null) showBanner("");  // connecting the first time
    else showBanner(`NO CONNECTION to the run since ${view.droppedAt.toLocaleTimeString()}: what the page shows is `
      + `stale (its last tick ${view.window[1]}${s.paused ? ", PAUSED then" : ""}) and the controls are off; ${again}`, true);
  }
  else if (silent) {
    showBanner(`NO WORD from the run for ${silent} s: what the page shows may be stale (its last tick `
      + `${view.window[1]}${s.paused ? ", PAUSED then" : ""}); resume, step and force are off until it `
      + "speaks again; pause and stop still go", true);
  }
  else if (view.finished) showBanner("the run ended: " + view.finished, false);
  else if (s.paused) {
    const since = s.paused_tick !== undefined && s.paused_tick !== null
      ? ` for ${duration((view.window[1] - s.paused_tick) * SLOT)}` : "";
    const sleeps = s.sleep_note ? ` (${s.sleep_note})` : "";
    // held at the mission's end (a breakpoint or a step on its last tick): nothing to go
    // back to, and a resume ends the run (the banner said it went back to the mission's mode)
    const next = s.held_end ? `the mission ended: ${s.held_end}; resume or step ends the run with it, stop as on Ctrl-C`
      : "resume goes back to the mission's mode";
    showBanner(`PAUSED${since}${sleeps} — ` + (s.pause_reason || "") + ` (robot stopped, in Passive; ${next})`, false);
  }
  else showBanner("");
  robotTitle();
}

function setTitle(action, title) {
  const button = $(action);
  if (button.title !== title) button.title = title;
}

// one of the four controls: off when ``off``, and while its control is on its way (pending)
const LABELS = {};
function controlButton(action, off) {
  const button = $(action), waiting = pending.has(action);
  LABELS[action] = LABELS[action] || button.textContent;
  const label = waiting ? PENDING_LABELS[action] : LABELS[action];
  button.disabled = off || waiting;
  if (button.textContent !== label) button.textContent = label;
  button.classList.toggle("pending", waiting);
  button.setAttribute("aria-busy", String(waiting));
}

// a phone's status bar (CSS shows it at 480 px and less): how the run is (running, PAUSED
// and for how long, how it ended), the OI mode and battery of the state shown; the link's
// badge beside it says whether that is stale
function statusBar(s) {
  const state = view.shownState, robot = state && state.robot, ended = view.shownEnded;
  let run = "", kind = "";
  if (view.finished) {
    // the outcome's word (success, interrupted, connection lost); a record's longer ending
    // ("the recorded run was stopped by the operator at ...") is the banner's to say
    const outcome = view.finished.split(/[:(]/)[0].trim();
    run = outcome.length <= 16 ? "ended: " + outcome : "ended"; kind = "ended";
  }
  else if (s.paused) {
    run = "PAUSED" + (s.paused_tick !== undefined && s.paused_tick !== null
      ? " " + duration((view.window[1] - s.paused_tick) * SLOT) : "");
    kind = "paused";
  }
  else if (view.header) run = "running";
  const texts = [[$("status-state"), run],
    [$("status-mode"), ended ? ended.mode : robot ? robot.mode : ""],
    [$("status-battery"), robot && robot.battery_percent !== undefined ? `${robot.battery_percent.toFixed(0)} %` : ""]];
  for (const [element, text] of texts) if (element.textContent !== text) element.textContent = text;
  $("status-state").className = kind;
  $("status-state").title = view.finished || "";
}

// the robot panel's title says which tick it shows; after the run's end, what its safe stop
// left the robot in (the server's state.ended: no tick shows it, the stream was paused)
function robotTitle() {
  let title = view.live ? "Robot" : `Robot at tick ${view.shownTick}`;
  const ended = view.shownEnded;
  if (ended) {
    title = ended.stopped ? `Robot after the run ended: stopped, ${ended.mode}`
      : `Robot: last seen before the run ended (${ended.stop_said})`;  // its mode: the row below
  }
  else if (view.finished && (view.live || view.shownTick >= view.window[1])) {
    // a record without its run's end (a killed run's) has no end to show: the server says so
    title = view.noEnd ? `Robot: its last recorded tick (${view.noEnd})`
      : "Robot: its last tick before the run ended";
  }
  const h2 = $("robot-panel").querySelector("h2");
  if (h2.textContent !== title) h2.textContent = title;
}

// what the timeline says once the monitor that served it has closed (the run ended, or a
// record's view was ended): it answers no seek, and a drag moved the slider and showed nothing
const CLOSED_TIMELINE = "the monitor has closed: no rewinding here (roomba-bt monitor FILE "
  + "rewinds a run recorded with --record)";

function updateTimeline() {
  const t = $("timeline");
  t.min = view.window[0]; t.max = view.window[1];
  if (view.live) t.value = view.window[1];
  // the run's server gone (ended, or another run served there): nothing to seek
  const closed = view.ended;
  t.disabled = view.header === null || closed;
  t.title = closed ? CLOSED_TIMELINE : "";
  // the stream's ticks and time (they go on while paused), named so beside the header's
  // mission time (which does not)
  const where = view.live ? `live · tick ${view.window[1]}`
    : `tick ${view.shownTick} · stream ${(view.shownTick * SLOT).toFixed(3)} s`;
  $("timeline-label").textContent = closed
    ? (view.live ? `last tick ${view.window[1]}` : where) + " · " + CLOSED_TIMELINE : where;
  $("live").disabled = view.live || (view.header && view.header.source === "record");
}

// GET a JSON answer; null when the run cannot be reached or refuses (the socket's close says it)
async function getJSON(url) {
  try {
    const reply = await fetch(url, { headers: headers() });
    return reply.ok ? await reply.json() : null;
  } catch (e) {
    return null;
  }
}

// an answer of another run than the page's (its own gone, another served on the port)
const otherRunsAnswer = (body) => !body || (body.header && body.header.run && body.header.run.id !== view.runId);

async function showTick(tick) {
  const body = await getJSON(`api/state?tick=${tick}`);
  if (otherRunsAnswer(body)) {
    // not shown (the run's server gone, or another run's): the slider back to the tick the
    // panels show, not left where it was dragged to over the end of the run
    $("timeline").value = view.shownTick;
    updateTimeline();
    return;
  }
  if (body.header) { view.window = [body.header.first_tick, body.header.last_tick]; }
  if (JSON.stringify(body.tree) !== JSON.stringify(view.tree)) buildTree(body.tree);
  view.events = body.events; view.session = body.session || view.session;
  setPath({ odometry: body.path.odometry, truth: body.path.truth, truthStart: firstTruth(body.path) });
  render(body.state);
}
function firstTruth() {
  // odometry starts at (0, 0, 0) where the true pose started
  return view.header && view.header.truth_start ? view.header.truth_start : null;
}

async function loadLiveState() {
  // the run as it is now and the path so far (a page opened mid-run, or connected again after
  // a drop: what it showed is stale); live updates append to the path
  const body = await getJSON("api/state");
  if (otherRunsAnswer(body)) return;
  const L = view.pathLive;
  L.odometry = body.path.odometry.concat(L.odometry);
  L.truth = body.path.truth.concat(L.truth);
  if (body.session) view.session = body.session;
  if (!view.liveState || view.liveState.tick < body.state.tick) view.liveState = body.state;
  if (view.live && view.liveState) render(view.liveState);
  updateControls();
}

// ------------------------------------------------------------------ live socket
function setBadge(text, on) {
  const badge = $("link"), className = on ? "badge on" : "badge off";
  if (badge.textContent !== text) badge.textContent = text;
  if (badge.className !== className) badge.className = className;
}

function connect() {
  // one socket a page: the browser's "online" comes while a try is still connecting too; a
  // second socket fed the page twice, and its twin's close marked a live page stale
  const current = view.socket;
  if (current && (current.readyState === WebSocket.CONNECTING || current.readyState === WebSocket.OPEN)) return;
  clearTimeout(view.retryTimer); view.retryTimer = null;
  // beside the page, as its other requests: the view-only link's page is under /view/
  const address = new URL("ws", location.href);
  address.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  address.search = token ? "?token=" + encodeURIComponent(token) : "";
  const ws = new WebSocket(address.href);
  view.socket = ws;
  // a socket that was closing when this one opened says nothing more (its close is no drop)
  const mine = (handler) => (ev) => { if (view.socket === ws) handler(ev); };
  ws.onopen = mine(() => {
    view.connected = true; view.droppedAt = null; view.retryMs = 1000; view.heardAt = Date.now();
    setBadge("connected", true);
  });
  ws.onclose = mine((ev) => {
    view.connected = false;
    if (view.finished && ev.code === GOING_AWAY) {  // the run is over: nothing to connect to
      view.ended = true; setBadge("ended", false); updateControls(); updateTimeline(); return;
    }
    if (view.droppedAt === null) view.droppedAt = new Date();
    setBadge("disconnected", false);
    reconnectLater();
    updateControls();
  });
  ws.onmessage = mine((ev) => {
    const msg = JSON.parse(ev.data);
    view.heardAt = Date.now();
    if (msg.sent !== undefined) view.sent = msg.sent;
    if (msg.type === "hello") { hello(msg.header); return; }
    if (msg.tree && JSON.stringify(msg.tree) !== JSON.stringify(view.tree)) {
      buildTree(msg.tree);  // a reload: a new tree from its root
      if (!view.live) showTick(view.shownTick);
    }
    if (msg.session) view.session = msg.session;
    if (msg.window) view.window = msg.window;
    if (msg.events) addEvents(msg.events);
    if (msg.no_end !== undefined) view.noEnd = msg.no_end;
    if (msg.finished !== undefined) view.finished = msg.finished;
    if (msg.path) appendLivePath(msg.path);
    if (msg.state) { view.liveState = msg.state; if (view.live) render(msg.state); else updateTimeline(); }
    else if (view.live && view.liveState) renderStatuses(view.liveState);
    updateControls();
  });
}

// after a drop: 1 s, then twice as long each failed try, at most 10 s
function reconnectLater() {
  if (view.retryTimer) return;
  const wait = view.retryMs;
  view.retryAt = Date.now() + wait;
  view.retryMs = Math.min(RETRY_MAX_MS, view.retryMs * 2);
  view.retryTimer = setTimeout(connect, wait);
}

// "14:03:27": a run's start (ISO 8601, UTC) in this browser's time
function clockOf(iso) {
  const d = new Date(iso);
  if (!iso || isNaN(d)) return "?";
  const two = (n) => String(n).padStart(2, "0");
  return `${two(d.getHours())}:${two(d.getMinutes())}:${two(d.getSeconds())}`;
}
// "robot 3: bump-and-turn on /dev/ttyUSB0, started 14:03:27": which run a header is (its
// label, run --label, first when it has one)
function runLabel(header) {
  const run = (header && header.run) || {};
  return `${run.label ? run.label + ": " : ""}${run.mission || (header && header.mission) || "?"}`
    + `${run.robot ? " on " + run.robot : ""}, started ${clockOf(run.started)}`;
}

// the socket found another run than the page's: it is not taken (its controls would drive
// another robot, silently); the page keeps what it showed, stale, and connects no more
function otherRun(run) {
  view.otherRun = run;
  view.connected = false; view.ended = true;
  clearTimeout(view.retryTimer); view.retryTimer = null;
  const ws = view.socket;
  view.socket = null;  // its close and messages are no longer the page's
  if (ws) ws.close();
  closeMenu();
  setBadge("another run", false);
  updateControls();
}

// a live run's page without controls says why where they would be: with none said, a
// viewer took the page for broken (a view-only link shown to a class, on a projector; a run
// started with --monitor-readonly). A recorded run's page is a player: its badge says so.
const NO_CONTROLS = {
  view: ["view only: the controls are on the control link",
    "opened with the view-only link (to share: a class, a projector): it shows the run; pausing, "
      + "stepping and stopping need the control link, the first monitor: URL the run printed"],
  readonly: ["read-only (--monitor-readonly): no controls on this page",
    "the run was started with --monitor-readonly: this page only shows it; the run's terminal "
      + "keys (p pause, r resume, n step, q stop) still work"],
};

function noControlsNote(header) {
  const why = header.view_only ? NO_CONTROLS.view
    : header.readonly && header.source !== "record" ? NO_CONTROLS.readonly : null;
  const note = $("no-controls");
  note.hidden = why === null;
  [note.textContent, note.title] = why || ["", ""];
}

function hello(header) {
  const run = header.run || {};
  if (view.runId === null) view.runId = run.id;
  else if (run.id !== view.runId) { otherRun(run); return; }
  const again = view.header !== null;  // connected again after a drop
  view.header = header; view.world = header.world;
  $("mission").textContent = header.mission;
  $("robot-name").textContent = run.robot ? "on " + run.robot : "";
  // a record made before its header held the start: unknown, not the time the page opened
  $("robot-name").title = run.started ? `run started ${clockOf(run.started)} (${run.started})`
    : "the run's start is unknown (its record was made before records held it)";
  $("run-label").textContent = run.label || "";
  $("run-label").hidden = !run.label;
  // a tab's title is cut from its end: the label first, so several robots' tabs differ
  document.title = `${run.label ? run.label + " · " : ""}${header.mission}`
    + `${run.robot ? " on " + run.robot : ""} · roomba-bt monitor`;
  $("source").textContent = header.source;
  // only the simulator knows where the robot truly is: no "true pose" legend on a robot's
  // page or a record's, which draw none
  $("legend-truth").hidden = header.source !== "simulator";
  noControlsNote(header);
  view.window = [header.first_tick, header.last_tick];
  view.noEnd = header.no_end === undefined ? view.noEnd : header.no_end;
  view.finished = header.finished === undefined ? view.finished : header.finished;
  if (JSON.stringify(header.tree) !== JSON.stringify(view.tree)) buildTree(header.tree);
  view.pathLive = { odometry: [], truth: [], truthStart: header.truth_start || null };
  view.events = [];  // the server sends its whole event log again after the hello
  const isRecord = header.source === "record";
  $("play").hidden = $("speed").hidden = !isRecord;
  if (isRecord) { view.live = false; showTick(again ? view.shownTick : header.first_tick); }
  else { loadLiveState(); if (!view.live) showTick(view.shownTick); }
  updateControls();
}

// ------------------------------------------------------------------ wiring
$("pause").onclick = () => control("pause");
$("resume").onclick = () => control("resume");
$("step").onclick = () => control("step");
$("stop").onclick = () => control("stop");
$("fit").onclick = fitTree;
$("follow").onclick = () => setFollow(!view.follow);
// reading elsewhere in the tree (the wheel, a finger): following would pull the view back
$("tree").addEventListener("wheel", () => setFollow(false), { passive: true });
$("tree").addEventListener("touchmove", () => setFollow(false), { passive: true });
// and the keyboard's Tab onto a node (not a click's focus): following pulled the view back
// to the running node, and the focused name, whose menu Enter opens, out of sight
$("tree").addEventListener("focusin", (ev) => { if (ev.target.matches(":focus-visible")) setFollow(false); });
$("zoom-in").onclick = () => zoom(1);
$("zoom-out").onclick = () => zoom(-1);
$("expand").onclick = () => { view.collapsed.clear(); applyCollapse(); };
$("collapse").onclick = () => { view.collapsed = new Set(view.tree.filter((n) => n.depth === 2 && n.children.length).map((n) => n.i)); applyCollapse(); };
$("timeline").addEventListener("input", (ev) => { view.live = false; stopPlay(); showTick(Number(ev.target.value)); });
$("live").onclick = () => { view.live = true; stopPlay(); if (view.liveState) render(view.liveState); };
$("play").onclick = () => { if (view.playing) stopPlay(); else startPlay(); };
function startPlay() {
  $("play").textContent = "⏸";
  let last = performance.now(), busy = false;
  view.playing = setInterval(async () => {
    if (busy) return;
    const now = performance.now(), speed = Number($("speed").value);
    const ticks = Math.max(1, Math.round((now - last) / 1000 * speed / SLOT));
    last = now;
    const next = Math.min(view.shownTick + ticks, view.window[1]);
    busy = true; await showTick(next); busy = false;
    if (next >= view.window[1]) stopPlay();
  }, 50);
}
function stopPlay() { if (view.playing) clearInterval(view.playing); view.playing = null; $("play").textContent = "▶"; }
document.addEventListener("keydown", (ev) => {
  if (ev.key === "Escape" && !$("node-menu").hidden) { closeMenu(); return; }
  if (ev.target.tagName === "INPUT" || ev.target.tagName === "SELECT" || !(view.header && view.header.controls)) return;
  // a browser's own shortcut is no control: Ctrl+R or Cmd+R (reload) read "r" too, and
  // resumed a paused robot; Ctrl+N (a new window) stepped it, Ctrl+P (print) paused it
  if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
  const key = PAGE_KEYS[ev.key];
  if (!key || pending.has(key)) return;  // on its way already: its button says so
  // a stale page asks nothing: the HTTP side may still reach the run while the socket is down,
  // and a resume from a page that no longer shows the run would set the robot going unseen
  const silent = MOTION.has(key) ? silentSeconds() : 0;
  if (!view.connected || view.finished || view.otherRun || silent) {
    const why = view.otherRun ? "a different run is now served here (reload to watch it)"
      : view.finished ? "the run has ended"
      : silent ? `no word from the run for ${silent} s (the page may be stale)`
      : "no connection to the run (the page is stale)";
    showAlert(`${key} NOT sent: ${why}; the robot does what it did`);
    return;
  }
  control(key);
});
window.addEventListener("resize", fitTree);
window.addEventListener("online", () => { if (!view.connected && !view.ended) connect(); });
$("alert-close").onclick = () => showAlert("");
// a phone cuts the banner to two lines: a tap shows it all, another cuts it again
$("banner").onclick = () => $("banner").classList.toggle("open");
// the countdown to the next try, and the run's silence (no message: nothing else calls it)
setInterval(() => { if (!view.ended) updateControls(); }, 500);
updateControls();
connect();
