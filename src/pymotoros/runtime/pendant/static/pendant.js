// The pymotoros web pendant: live state over /ws/state, buttons over POST /api/...
// Plain JavaScript, no library: everything is served by the simulator (works offline).
"use strict";
(function () {
  const M_BASE = 1000000;          // M-register n is IO address 1000000 + n (control API)
  const PLOT_SECONDS = 10;         // history shown by the plots
  const RECONNECT_MS = 1000;       // retry delay after the feed closed
  const PLOT_W = 560, PLOT_H = 200; // one command-vs-feedback plot per group, in pixels
  const COLORS = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#90a4ae", "#f06292"];
  const $ = (id) => document.getElementById(id);
  const state = { last: null, updates: 0, history: [], answeredAt: -1, view: { yaw: -0.7, pitch: 0.4, dist: 2.4, cx: 0, cy: 0, cz: 0.5 } };
  window.pendant = state;           // for debugging and the browser test

  function say(text) { $("message").textContent = text; }

  async function post(path, body, method) {
    const resp = await fetch(path, { method: method || "POST", headers: { "Content-Type": "application/json" },
                                     body: JSON.stringify(body === undefined ? {} : body) });
    const answer = await resp.json();
    if (!resp.ok) { say(answer.error || ("HTTP " + resp.status)); return null; }
    say(""); render(answer, false); state.answeredAt = answer.tick.count; return answer;
  }

  // A feed document is captured at a tick and may be sent after a button's answer was
  // rendered: one captured at or before the answer's tick may predate the press (the
  // E-stop light would go out again for a moment), so it is dropped; the next one is newer.
  function fromFeed(doc) {
    if (doc.tick.count <= state.answeredAt) return false;
    render(doc, true);
    return true;
  }
  state.fromFeed = fromFeed;        // the browser test feeds it a stale document

  async function readIo(address, out) {
    const resp = await fetch("/api/io/" + address);
    const answer = await resp.json();
    out.textContent = resp.ok ? ("= " + answer.value) : answer.error;
  }

  const yn = (v) => v ? '<span class="yes">ON</span>' : '<span class="no">OFF</span>';
  function setOn(id, on) { $(id).classList.toggle("on", !!on); }

  function fmt(rad) {
    return $("units-rad").checked ? rad.toFixed(4) : (rad * 180 / Math.PI).toFixed(2);
  }

  // Poses are in base (base_link raised by the S-axis height, from the robot model),
  // obstacles in base_link: every pose on screen says which (issue 29).
  function frameNote(g) {
    const h = g.base_frame ? g.base_frame.above_base_link_m : null;
    if (h === null) return "in base coordinates";
    return h === 0 ? "in base (= base_link)" : `in base (${h.toFixed(3)} m above base_link, the S-axis height)`;
  }

  function renderGroups(groups) {
    const unit = $("units-rad").checked ? "rad" : "deg";
    let html = "";
    for (const g of groups) {
      html += `<h3>${g.name}: queue ${g.queue}, tool ${g.tool}</h3><table class="joints"><tr><th></th>`;
      html += g.joint_names.map((n) => `<th>${n}</th>`).join("") + "</tr>";
      html += `<tr><th>command (${unit})</th>` + g.command_rad.map((v, i) => `<td class="cmd" data-joint="${i}">${fmt(v)}</td>`).join("") + "</tr>";
      html += `<tr><th>feedback (${unit})</th>` + g.feedback_rad.map((v, i) => `<td class="fb" data-joint="${i}">${fmt(v)}</td>`).join("") + "</tr></table>";
      if (g.tcp) {
        const p = g.tcp.feedback;
        html += `<div class="small tcp-pose">TCP x ${(p[0] * 1000).toFixed(1)} y ${(p[1] * 1000).toFixed(1)} z ${(p[2] * 1000).toFixed(1)} mm,` +
                ` rx ${(p[3] * 180 / Math.PI).toFixed(2)} ry ${(p[4] * 180 / Math.PI).toFixed(2)} rz ${(p[5] * 180 / Math.PI).toFixed(2)}°,` +
                ` ${g.tcp.speed_mm_s.feedback.toFixed(1)} mm/s ${frameNote(g)}</div>`;
      }
    }
    $("groups").innerHTML = html;
  }

  function render(doc, live) {
    state.last = doc;
    if (live) state.updates += 1;
    $("st-mode").textContent = doc.mode.toUpperCase();
    $("st-remote").innerHTML = yn(doc.remote);
    $("st-servo").innerHTML = yn(doc.servo);
    $("st-estop").innerHTML = doc.estop ? '<span class="no">PRESSED</span>' : '<span class="yes">released</span>';
    $("st-hold").innerHTML = yn(doc.hold);
    $("st-ready").innerHTML = doc.motion_ready ? '<span class="yes">ready</span>' : '<span class="no">not ready</span>';
    $("st-motoros").textContent = doc.motoros;
    const extra = doc.pendant || {};
    // eco mode: servo power on, drives off after the idle time; brakes hold the axes
    $("st-eco").innerHTML = extra.eco === undefined ? "–" :
      (extra.eco ? '<span class="no">ECO: drives off, brakes on</span>' : '<span class="yes">off</span>');
    if (extra.not_ready) {
      const n = extra.not_ready;
      $("st-notready").textContent = doc.motion_ready ? "–" : `${n.subcode} ${n.name}: ${n.meaning}${n.why ? " (" + n.why + ")" : ""}`;
    }
    if (extra.jobs) $("st-jobs").textContent = extra.jobs.length ? extra.jobs.map((j) => `${j.job} line ${j.line}`).join(", ") : "no job running";
    if (extra.outputs) $("st-outputs").innerHTML = extra.outputs.map((o) => `<span class="${o.value ? "yes" : "no"}" title="${o.name}">${o.value}</span>`).join(" ");
    if (extra.clients) {
      const c = extra.clients, p0 = doc.ports;
      $("st-clients").textContent = `motion ${c.motion} on ${p0.motion ?? "–"}, state ${c.state} on ${p0.state ?? "–"}, io ${c.io} on ${p0.io ?? "–"}`;
    }
    const p = doc.ports;
    $("st-ports").textContent = `motion ${p.motion ?? "closed"}, state ${p.state ?? "closed"}, io ${p.io ?? "closed"}`;
    $("st-pfl").textContent = doc.pfl;
    $("st-fsu").textContent = doc.fsu.joint_speed_pct === null && doc.fsu.tcp_speed_mm_s === null ? "off" :
      `${doc.fsu.joint_speed_pct ?? "–"} % joint, ${doc.fsu.tcp_speed_mm_s ?? "–"} mm/s TCP`;
    const t = doc.tick;
    $("st-tick").textContent = `${t.count} ticks of ${t.period_ms} ms, lateness p50 ${t.lateness_ms.p50.toFixed(3)} ` +
      `p99 ${t.lateness_ms.p99.toFixed(3)} max ${t.lateness_ms.max.toFixed(3)} ms, ${t.overruns} overruns`;
    const faults = doc.alarms.map((a) => ["alarm", a]).concat((extra.errors || []).map((e) => ["error", e]));
    $("alarms").innerHTML = faults.length === 0 ? "<li>none</li>" :
      faults.map(([kind, a]) => `<li class="${kind}">${kind} ${a.code} / ${a.subcode}: ${escapeHtml(a.text)}</li>`).join("");
    $("events").innerHTML = doc.events.length === 0 ? "<li>none</li>" :
      doc.events.slice(-8).map((e) => `<li>${e.t.toFixed(2)} s ${escapeHtml(e.action)}${e.error ? " (" + escapeHtml(e.error) + ")" : ""}</li>`).join("");
    $("estop-light").classList.toggle("on", doc.estop);
    setOn("btn-estop", doc.estop); setOn("btn-hold", doc.hold); setOn("btn-remote", doc.remote);
    setOn("btn-servo", doc.servo); $("btn-mode").textContent = doc.mode === "play" ? "PLAY → TEACH" : "TEACH → PLAY";
    $("safety-row").style.display = doc.pfl === "off" ? "none" : "flex";
    renderGroups(doc.groups);
    if (live) {
      const now = performance.now() / 1000;
      state.history.push({ t: now, groups: doc.groups.map((g) => ({ c: g.command_rad, f: g.feedback_rad })), late: t.lateness_ms.p99 });
      while (state.history.length && state.history[0].t < now - PLOT_SECONDS) state.history.shift();
      drawPlots(now);
    }
    if (doc.groups.some((g) => g.frames)) draw3d();
  }

  function escapeHtml(s) { return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" }[c])); }

  // ------------------------------------------------------------------ plots
  // Each plot: a title, value ticks on the left (in the plot's unit), time ticks below
  // (seconds before now), and a legend of the joints in their colours under it.
  const PLOT_PAD = { left: 46, right: 8, top: 18, bottom: 16 };
  const LEGEND_ROW = 13;
  const TEXT = "#aab", GRID = "#2a3138";

  // About `count` round tick values covering lo..hi (steps of 1, 2 or 5 × 10^k).
  function ticks(lo, hi, count) {
    const raw = (hi - lo) / count, mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw);
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    return { values: out, digits: Math.max(0, -Math.floor(Math.log10(step))) };
  }

  // The value range with a margin; a flat line (a robot at rest) gets ±0.1.
  function range(values) {
    let lo = Math.min(...values), hi = Math.max(...values);
    if (!isFinite(lo)) { lo = 0; hi = 0; }
    if (hi - lo < 1e-6) { lo -= 0.1; hi += 0.1; }
    const m = (hi - lo) * 0.05;
    return [lo - m, hi + m];
  }

  // Legend entries laid out in rows that fit the width; returns [{x, row, text, color}].
  function legendLayout(ctx, entries, width) {
    const out = []; let x = PLOT_PAD.left, row = 0;
    for (const [text, color] of entries) {
      const w = 18 + ctx.measureText(text).width + 10;
      if (x + w > width && x > PLOT_PAD.left) { x = PLOT_PAD.left; row += 1; }
      out.push({ x, row, text, color }); x += w;
    }
    return out;
  }

  // Axes, ticks and legend; returns the plot's inner box and a value -> y mapping.
  function drawFrame(ctx, w, h, title, unit, lo, hi, legend) {
    ctx.font = "10px sans-serif"; ctx.textBaseline = "middle";
    const items = legendLayout(ctx, legend, w - PLOT_PAD.right);
    const rows = items.length ? items[items.length - 1].row + 1 : 0;
    const box = { x0: PLOT_PAD.left, x1: w - PLOT_PAD.right, y0: PLOT_PAD.top,
                  y1: h - PLOT_PAD.bottom - rows * LEGEND_ROW };
    const y = (v) => box.y1 - (v - lo) / (hi - lo) * (box.y1 - box.y0);
    ctx.fillStyle = TEXT; ctx.textAlign = "left"; ctx.fillText(`${title} (${unit})`, 6, 9);
    const vt = ticks(lo, hi, 4);
    ctx.textAlign = "right";
    for (const v of vt.values) {
      ctx.strokeStyle = GRID; ctx.beginPath(); ctx.moveTo(box.x0, y(v)); ctx.lineTo(box.x1, y(v)); ctx.stroke();
      ctx.fillStyle = TEXT; ctx.fillText(v.toFixed(vt.digits), box.x0 - 4, y(v));
    }
    ctx.textAlign = "center";
    for (let s = 0; s <= PLOT_SECONDS; s += 2) {
      const x = box.x1 - s / PLOT_SECONDS * (box.x1 - box.x0);
      ctx.strokeStyle = GRID; ctx.beginPath(); ctx.moveTo(x, box.y0); ctx.lineTo(x, box.y1); ctx.stroke();
      ctx.fillStyle = TEXT; ctx.fillText(s === 0 ? "now" : `−${s} s`, Math.min(x, box.x1 - 10), box.y1 + 8);
    }
    ctx.textAlign = "left";
    for (const it of items) {
      const ly = box.y1 + PLOT_PAD.bottom + it.row * LEGEND_ROW + 4;
      ctx.strokeStyle = it.color; ctx.lineWidth = 2; ctx.beginPath(); ctx.moveTo(it.x, ly); ctx.lineTo(it.x + 14, ly); ctx.stroke();
      ctx.lineWidth = 1; ctx.fillStyle = TEXT; ctx.fillText(it.text, it.x + 18, ly);
    }
    return { box, y };
  }

  function drawSeries(ctx, frame, now, series, color, dash) {
    const { box, y } = frame;
    ctx.save(); ctx.beginPath(); ctx.rect(box.x0, box.y0, box.x1 - box.x0, box.y1 - box.y0); ctx.clip();
    ctx.strokeStyle = color; ctx.setLineDash(dash || []); ctx.beginPath();
    series.forEach(([t, v], i) => {
      const x = box.x1 - (now - t) / PLOT_SECONDS * (box.x1 - box.x0);
      if (i === 0) ctx.moveTo(x, y(v)); else ctx.lineTo(x, y(v));
    });
    ctx.stroke(); ctx.restore();
  }

  // One canvas per group, made when the group first appears (SDA10F: two arms, two torso axes).
  function plotCanvas(gi) {
    const box = $("plot-groups");
    while (box.children.length <= gi) {
      const c = document.createElement("canvas");
      c.width = PLOT_W; c.height = PLOT_H; c.className = "plot-joints";
      c.id = "plot-joints-" + box.children.length;
      box.appendChild(c);
    }
    return box.children[gi];
  }

  function drawPlots(now) {
    const latest = state.history.length ? state.history[state.history.length - 1].groups : [];
    latest.forEach((g, gi) => {
      const c = plotCanvas(gi), ctx = c.getContext("2d");
      ctx.clearRect(0, 0, c.width, c.height);
      const rows = state.history.filter((s) => s.groups[gi]);
      const [lo, hi] = range(rows.flatMap((s) => s.groups[gi].c.concat(s.groups[gi].f)));
      const group = state.last && state.last.groups[gi];
      const name = group ? group.name : "group " + (gi + 1);
      const names = group ? group.joint_names : g.c.map((_, j) => "joint " + (j + 1));
      const frame = drawFrame(ctx, c.width, c.height, `${name}: dashed command, solid feedback`, "rad", lo, hi,
                              names.map((n, j) => [n, COLORS[j % COLORS.length]]));
      for (let j = 0; j < g.c.length; j++) {
        drawSeries(ctx, frame, now, rows.map((s) => [s.t, s.groups[gi].c[j]]), COLORS[j % COLORS.length], [4, 3]);
        drawSeries(ctx, frame, now, rows.map((s) => [s.t, s.groups[gi].f[j]]), COLORS[j % COLORS.length]);
      }
    });
    const l = $("plot-lateness"), lctx = l.getContext("2d");
    lctx.clearRect(0, 0, l.width, l.height);
    const hi = Math.max(1, ...state.history.map((s) => s.late)) * 1.05;
    const frame = drawFrame(lctx, l.width, l.height, "interpolation loop lateness, p99", "ms", 0, hi, []);
    drawSeries(lctx, frame, now, state.history.map((s) => [s.t, s.late]), "#ffb74d");
  }

  // ------------------------------------------------------------------ 3D view
  // A small perspective projection of the joint positions (z up), links as thick lines.
  function project(p, v, w, h) {
    const x = p[0] - v.cx, y = p[1] - v.cy, z = p[2] - v.cz;
    const cy = Math.cos(v.yaw), sy = Math.sin(v.yaw), cp = Math.cos(v.pitch), sp = Math.sin(v.pitch);
    const xr = cy * x - sy * y, yr = sy * x + cy * y;          // yaw about z
    const depth = v.dist + cp * yr - sp * z;                   // camera looks along +y, tilted down
    const up = sp * yr + cp * z;
    const f = h * 1.2 / Math.max(0.1, depth);
    return [w / 2 + xr * f, h / 2 - up * f, depth];
  }

  // The workspace (GET /api/pendant/state: pendant.workspace, groups[].capsules), in the
  // workspace frame: obstacles as translucent solids, red while the robot touches them,
  // and the robot's collision capsules (the shapes the twin's contact check uses).
  const OBSTACLE = { fill: "rgba(90,140,200,0.30)", line: "#6f9fd8" };
  const TOUCHED = { fill: "rgba(235,50,50,0.55)", line: "#ff4040" };
  const CAPSULE = "rgba(120,210,150,0.28)";
  const RING = 24;                  // segments of a drawn circle

  function place(o, p) {            // a point of the obstacle's own frame → workspace frame
    const r = o.rot;
    return [o.xyz[0] + r[0] * p[0] + r[1] * p[1] + r[2] * p[2],
            o.xyz[1] + r[3] * p[0] + r[4] * p[1] + r[5] * p[2],
            o.xyz[2] + r[6] * p[0] + r[7] * p[1] + r[8] * p[2]];
  }

  function ring(radius, z, plane) { // a circle in the obstacle's frame (plane: "xy", "xz", "yz")
    const pts = [];
    for (let i = 0; i < RING; i++) {
      const a = 2 * Math.PI * i / RING, u = radius * Math.cos(a), w = radius * Math.sin(a);
      pts.push(plane === "xz" ? [u, 0, w] : plane === "yz" ? [0, u, w] : [u, w, z]);
    }
    return pts;
  }

  function obstacleFaces(o) {       // closed polygons in the obstacle's frame
    if (o.shape === "box") {
      const [x, y, z] = o.size.map((s) => s / 2);
      const c = (i, j, k) => [i * x, j * y, k * z];
      return [[c(-1, -1, -1), c(1, -1, -1), c(1, 1, -1), c(-1, 1, -1)], [c(-1, -1, 1), c(1, -1, 1), c(1, 1, 1), c(-1, 1, 1)],
              [c(-1, -1, -1), c(1, -1, -1), c(1, -1, 1), c(-1, -1, 1)], [c(-1, 1, -1), c(1, 1, -1), c(1, 1, 1), c(-1, 1, 1)],
              [c(-1, -1, -1), c(-1, 1, -1), c(-1, 1, 1), c(-1, -1, 1)], [c(1, -1, -1), c(1, 1, -1), c(1, 1, 1), c(1, -1, 1)]];
    }
    if (o.shape === "cylinder") {
      const [r, len] = o.size, faces = [ring(r, -len / 2, "xy"), ring(r, len / 2, "xy")];
      for (let i = 0; i < RING; i += RING / 4) {
        const a = 2 * Math.PI * i / RING, p = [r * Math.cos(a), r * Math.sin(a)];
        faces.push([[p[0], p[1], -len / 2], [p[0], p[1], len / 2]]);
      }
      return faces;
    }
    return [ring(o.size[0], 0, "xy"), ring(o.size[0], 0, "xz"), ring(o.size[0], 0, "yz")];
  }

  function drawObstacle(ctx, o, v, w, h) {
    const look = o.contact ? TOUCHED : OBSTACLE;
    ctx.fillStyle = look.fill; ctx.strokeStyle = look.line; ctx.lineWidth = o.contact ? 2 : 1;
    if (o.shape === "sphere") {     // its outline: a disc of the projected radius
      const c = project(o.xyz, v, w, h), f = h * 1.2 / Math.max(0.1, c[2]);
      ctx.beginPath(); ctx.arc(c[0], c[1], o.size[0] * f, 0, 2 * Math.PI); ctx.fill();
    }
    for (const face of obstacleFaces(o)) {
      const pts = face.map((p) => project(place(o, p), v, w, h));
      ctx.beginPath(); ctx.moveTo(pts[0][0], pts[0][1]);
      for (const q of pts.slice(1)) ctx.lineTo(q[0], q[1]);
      if (pts.length > 2) { ctx.closePath(); if (o.shape !== "sphere") ctx.fill(); }
      ctx.stroke();
    }
    const c = project(o.xyz, v, w, h);
    ctx.fillStyle = look.line; ctx.fillText(o.name, c[0] + 4, c[1] - 4);
  }

  // The tool in force (groups[].tool_body): its shape as the contact check mounts it,
  // the line tool0 → TCP and the TCP itself, so a tool touching an obstacle is seen
  // touching it.
  const TOOL = { fill: "rgba(255,213,79,0.45)", line: "#ffd54f" };

  function drawTool(ctx, t, shift, v, w, h) {
    const onto = (p) => shift(p);
    if (t.shape === "capsule") {      // along its own z: a thick round-capped line
      const half = t.size[1] / 2, r = t.rot;
      const a = [t.xyz[0] - r[2] * half, t.xyz[1] - r[5] * half, t.xyz[2] - r[8] * half];
      const b = [t.xyz[0] + r[2] * half, t.xyz[1] + r[5] * half, t.xyz[2] + r[8] * half];
      const pa = project(onto(a), v, w, h), pb = project(onto(b), v, w, h);
      ctx.strokeStyle = TOOL.fill; ctx.lineCap = "round";
      ctx.lineWidth = Math.max(2, 2 * t.size[0] * h * 1.2 / Math.max(0.1, (pa[2] + pb[2]) / 2));
      ctx.beginPath(); ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pb[0], pb[1]); ctx.stroke();
    } else if (t.shape) {             // box, cylinder, sphere: drawn as an obstacle is
      const o = { xyz: onto(t.xyz), rot: t.rot, size: t.size, shape: t.shape };
      ctx.fillStyle = TOOL.fill; ctx.strokeStyle = TOOL.line; ctx.lineWidth = 1;
      if (o.shape === "sphere") {
        const c = project(o.xyz, v, w, h), f = h * 1.2 / Math.max(0.1, c[2]);
        ctx.beginPath(); ctx.arc(c[0], c[1], o.size[0] * f, 0, 2 * Math.PI); ctx.fill();
      }
      for (const face of obstacleFaces(o)) {
        const pts = face.map((p) => project(place(o, p), v, w, h));
        ctx.beginPath(); ctx.moveTo(pts[0][0], pts[0][1]);
        for (const q of pts.slice(1)) ctx.lineTo(q[0], q[1]);
        if (pts.length > 2) { ctx.closePath(); if (o.shape !== "sphere") ctx.fill(); }
        ctx.stroke();
      }
    }
    const a = project(onto(t.tool0), v, w, h), b = project(onto(t.tcp), v, w, h);
    ctx.strokeStyle = TOOL.line; ctx.lineWidth = 2; ctx.setLineDash([4, 3]);
    ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke(); ctx.setLineDash([]);
    ctx.fillStyle = TOOL.line; ctx.beginPath(); ctx.arc(b[0], b[1], 4, 0, 2 * Math.PI); ctx.fill();
    ctx.fillText(`TCP (tool ${t.number}${t.name ? " " + t.name : ""})`, b[0] + 6, b[1] + 4);
  }

  // A frame's axes (x, y, z) at a point, 0.2 m long, with its name: the obstacles'
  // base_link at the robot's foot and the poses' base above it. No pure red: red is what
  // a touched obstacle is drawn in (the browser test counts red pixels).
  const AXES = [["x", "#ffcc80"], ["y", "#9ccc65"], ["z", "#64b5f6"]];
  function drawFrameAxes(ctx, origin, label, v, w, h) {
    const o = project(origin, v, w, h);
    AXES.forEach(([name, color], k) => {
      const tip = origin.slice(); tip[k] += 0.2;
      const p = project(tip, v, w, h);
      ctx.strokeStyle = color; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.moveTo(o[0], o[1]); ctx.lineTo(p[0], p[1]); ctx.stroke();
      ctx.fillStyle = color; ctx.fillText(name, p[0] + 2, p[1] - 2);
    });
    ctx.fillStyle = "#cfd8dc"; ctx.fillText(label, o[0] - 8 - ctx.measureText(label).width, o[1] + 4);
  }

  function drawCapsules(ctx, capsules, shift, v, w, h) {
    ctx.strokeStyle = CAPSULE; ctx.lineCap = "round";
    for (const k of capsules) {     // [ax, ay, az, bx, by, bz, radius]: a thick round-capped line
      const a = project(shift([k[0], k[1], k[2]]), v, w, h), b = project(shift([k[3], k[4], k[5]]), v, w, h);
      ctx.lineWidth = Math.max(1, 2 * k[6] * h * 1.2 / Math.max(0.1, (a[2] + b[2]) / 2));
      ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke();
    }
  }

  function draw3d() {
    const c = $("view3d"), ctx = c.getContext("2d"), v = state.view, w = c.width, h = c.height;
    ctx.clearRect(0, 0, w, h);
    ctx.strokeStyle = "#2c3540"; ctx.lineWidth = 1;               // floor grid, 0.25 m
    for (let i = -4; i <= 4; i++) {
      const a = project([i * 0.25, -1, 0], v, w, h), b = project([i * 0.25, 1, 0], v, w, h);
      const d = project([-1, i * 0.25, 0], v, w, h), e = project([1, i * 0.25, 0], v, w, h);
      ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.moveTo(d[0], d[1]); ctx.lineTo(e[0], e[1]); ctx.stroke();
    }
    const obstacles = (state.last && state.last.pendant && state.last.pendant.workspace) || [];
    for (const o of obstacles) drawObstacle(ctx, o, v, w, h);
    const groups = (state.last && state.last.groups) || [];
    const wsFrame = (state.last && state.last.pendant && state.last.pendant.workspace_frame) || null;
    const frames = [];
    if (wsFrame) {                  // the frame every obstacle's xyz is in
      const label = `${wsFrame.name}${wsFrame.of ? " " + wsFrame.of : ""} (obstacles)`;
      drawFrameAxes(ctx, [0, 0, 0], label, v, w, h);
      frames.push(label);
    }
    const tools = [];
    groups.forEach((g, gi) => {
      if (!g.frames) return;
      const shift = (p) => [p[0], p[1] + gi * 1.5, p[2]];          // groups side by side
      if (g.capsules) drawCapsules(ctx, g.capsules, shift, v, w, h);
      if (g.tool_body) {
        drawTool(ctx, g.tool_body, shift, v, w, h);
        tools.push({ group: g.name, number: g.tool_body.number, name: g.tool_body.name, shape: g.tool_body.shape,
                     size: g.tool_body.size || null, tcp: g.tool_body.tcp, color: TOOL.fill });
      }
      if (g.base_frame && g.base_frame.above_base_link_m > 0) {   // the frame of the poses
        const label = `base ${g.name} (poses, +${g.base_frame.above_base_link_m.toFixed(3)} m)`;
        drawFrameAxes(ctx, shift([0, 0, g.base_frame.above_base_link_m]), label, v, w, h);
        frames.push(label);
      }
      for (const [pts, color, width] of [[g.frames.command, "rgba(200,200,200,0.35)", 9], [g.frames.feedback, "#f5a623", 11]]) {
        const all = [[0, 0, 0]].concat(pts).map((p) => project(shift(p), v, w, h));
        ctx.lineCap = "round"; ctx.lineJoin = "round";
        for (let i = 1; i < all.length; i++) {
          ctx.strokeStyle = color; ctx.lineWidth = Math.max(2, width * (i < all.length - 3 ? 1 : 0.5) * 3 / all[i][2]);
          ctx.beginPath(); ctx.moveTo(all[i - 1][0], all[i - 1][1]); ctx.lineTo(all[i][0], all[i][1]); ctx.stroke();
        }
        ctx.fillStyle = color === "#f5a623" ? "#333" : "rgba(0,0,0,0)";
        for (const q of all) { ctx.beginPath(); ctx.arc(q[0], q[1], 3, 0, 2 * Math.PI); ctx.fill(); }
      }
      const base = project(shift([0, 0, 0]), v, w, h);
      ctx.fillStyle = "#aab"; ctx.fillText(g.name, base[0] + 8, base[1] + 14);
    });
    state.scene = {                 // what the view shows (for the browser test)
      obstacles: obstacles.map((o) => ({ name: o.name, shape: o.shape, contact: o.contact, color: (o.contact ? TOUCHED : OBSTACLE).fill })),
      capsules: groups.reduce((n, g) => n + (g.capsules ? g.capsules.length : 0), 0),
      tools, frames,
    };
  }

  function setupOrbit() {
    const c = $("view3d"); let drag = null;
    c.addEventListener("mousedown", (e) => { drag = [e.clientX, e.clientY]; });
    window.addEventListener("mouseup", () => { drag = null; });
    window.addEventListener("mousemove", (e) => {
      if (!drag) return;
      state.view.yaw += (e.clientX - drag[0]) * 0.01;
      state.view.pitch = Math.max(-1.4, Math.min(1.4, state.view.pitch + (e.clientY - drag[1]) * 0.01));
      drag = [e.clientX, e.clientY]; draw3d();
    });
    c.addEventListener("wheel", (e) => {
      e.preventDefault(); state.view.dist = Math.max(0.5, Math.min(20, state.view.dist * (e.deltaY > 0 ? 1.1 : 0.9))); draw3d();
    }, { passive: false });
  }

  // ------------------------------------------------------------------ feed
  function connect() {
    const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws/state");
    ws.onopen = () => {             // a restarted simulator counts its ticks from zero again
      state.answeredAt = -1; $("link").textContent = "live"; $("link").className = "badge on";
    };
    ws.onmessage = (m) => fromFeed(JSON.parse(m.data));
    ws.onclose = () => { $("link").textContent = "disconnected"; $("link").className = "badge off"; setTimeout(connect, RECONNECT_MS); };
  }

  // ------------------------------------------------------------------ buttons
  // The actions and their paths come from the simulator's declarations
  // (GET /api/pendant/actions): the buttons call an action by name, never a path of their own.
  const actions = {};
  state.actions = actions;          // for the browser test
  async function loadActions() {
    try {
      const resp = await fetch("/api/pendant/actions");
      for (const a of await resp.json()) actions[a.name] = a;
    } catch (err) { say("cannot read the list of actions: " + err); return; }
    boundInputs();
    fillActionPicker();
  }
  // The number inputs take their limits from the declarations, not from copies here.
  function boundInputs() {
    const inputs = [["alarm-code", "alarm", "code"], ["fsu-pct", "fsu", "joint_speed_pct"],
                    ["io-value", "io", "value"], ["m-value", "io", "value"]];
    for (const [id, name, key] of inputs) {
      const p = actions[name] && actions[name].params.find((q) => q.name === key);
      if (!p) continue;
      const low = p.ge !== null ? p.ge : p.gt;
      if (low !== null) $(id).min = low;
      if (p.le !== null) $(id).max = p.le;
      $(id).title = p.doc + (p.bounds ? " (" + p.bounds + ")" : "");
    }
  }
  function act(name, body) {
    const a = actions[name];
    if (!a) { say("the simulator has no action " + name); return null; }
    const rest = Object.assign({}, body || {});
    const path = a.path.replace(/\{(\w+)\}/g, (_, key) => {   // a parameter given in the path
      const value = rest[key]; delete rest[key]; return encodeURIComponent(value);
    });
    return post(path, rest, a.method);
  }

  function paramHint(a) {
    return a.params.map((p) => `${p.name}: ${p.kind}${p.bounds ? " " + p.bounds : ""}` +
      `${p.choices.length ? " (" + p.choices.join("|") + ")" : ""}${p.required ? "" : " optional"}`).join(", ");
  }
  // Every declared action, also those without a button of their own: name + JSON parameters.
  function fillActionPicker() {
    const row = document.createElement("div");
    row.className = "row";
    row.innerHTML = '<label>Action <select id="action-name"></select></label>' +
      '<input id="action-params" size="32" placeholder="{}">' +
      '<button id="btn-action">Run</button>';
    $("message").before(row);
    const select = $("action-name");
    for (const a of Object.values(actions)) {
      const opt = document.createElement("option");
      opt.value = a.name; opt.textContent = a.name; opt.title = a.doc;
      select.appendChild(opt);
    }
    const hint = () => {
      const a = actions[select.value];
      $("action-params").title = a ? a.doc + (a.params.length ? " Parameters: " + paramHint(a) : "") : "";
      $("action-params").placeholder = a && a.params.length ? paramHint(a) : "{}";
    };
    select.onchange = hint; hint();
    $("btn-action").onclick = () => {
      let body;
      try { body = JSON.parse($("action-params").value || "{}"); } catch (err) { say("parameters: not JSON: " + err); return; }
      act(select.value, body);
    };
  }

  function wire() {
    const last = () => state.last || {};
    $("btn-estop").onclick = () => act("estop", { pressed: !last().estop });
    $("btn-hold").onclick = () => act("hold", { on: !last().hold });
    $("btn-mode").onclick = () => act("mode", { mode: last().mode === "play" ? "teach" : "play" });
    $("btn-remote").onclick = () => act("remote", { on: !last().remote });
    $("btn-servo").onclick = () => act("servo", { on: !last().servo });
    $("btn-reset").onclick = () => act("reset");
    $("btn-alarm").onclick = () => act("alarm", { code: Number($("alarm-code").value), text: $("alarm-text").value });
    $("btn-pfl").onclick = () => act("pfl", { event: "contact" });
    $("btn-fsu").onclick = () => act("fsu", { joint_speed_pct: Number($("fsu-pct").value) });
    $("btn-fsu-off").onclick = () => act("fsu", { off: true });
    $("btn-io-read").onclick = () => readIo(Number($("io-address").value), $("io-result"));
    $("btn-io-write").onclick = () => act("io", { address: Number($("io-address").value), value: Number($("io-value").value) });
    $("btn-m-read").onclick = () => readIo(M_BASE + Number($("m-number").value), $("m-result"));
    $("btn-m-write").onclick = () => act("io", { address: M_BASE + Number($("m-number").value), value: Number($("m-value").value) });
    $("btn-scenario").onclick = async () => {
      const file = $("scenario-file").files[0];
      if (!file) { say("choose a scenario file (.toml with [[events]], or JSON {\"events\": [...]}) first"); return; }
      if (file.name.toLowerCase().endsWith(".toml")) {   // parsed by the simulator, as --scenario
        post("/api/pendant/scenario", { name: file.name, toml: await file.text() });
        return;
      }
      let doc;
      try { doc = JSON.parse(await file.text()); } catch (err) { say("not JSON: " + err); return; }
      act("scenario", Array.isArray(doc) ? { events: doc } : doc);
    };
    $("units-rad").onchange = () => state.last && renderGroups(state.last.groups);
  }

  wire(); loadActions(); setupOrbit(); connect();
})();
