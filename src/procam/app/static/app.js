// procam app: the page's behaviour. Plain JS, no build step; every request carries the session's token.
"use strict";
const TOKEN = document.querySelector('meta[name="procam-token"]').content;
const $ = (id) => document.getElementById(id);
let STATE = null;
let JOB = null;          // the running job (its dict) or null
let PREVIEW_BUSY = false;
let frames = [];
const DRAWN = { frames: 0, advice: 0, lastAdvice: null };

function url(path) { return path + (path.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(TOKEN); }
function fileUrl(name, download) { return url("files/" + name.split("/").map(encodeURIComponent).join("/")) + (download ? "&download=1" : "") + "&t=" + Date.now(); }

// The changes (POSTs) go to the server one at a time, in the order they were made: each is sent once the one
// before has been answered. Sent together, two requests on two connections are handled in either order, and a
// photo taken right after choosing the board's pose could be taken at the pose before.
let CHANGES = Promise.resolve();

async function api(path, body) {
  const opts = { headers: { "X-Procam-Token": TOKEN } };
  if (body === undefined) return answer(await fetch(path, opts));
  opts.method = "POST";
  opts.headers["Content-Type"] = "application/json";
  opts.body = JSON.stringify(body);
  const before = CHANGES;
  let done;
  CHANGES = new Promise((r) => { done = r; });
  try {
    await before;
    return await answer(await fetch(path, opts));
  } finally {
    done();
  }
}

async function answer(r) {
  const data = await r.json().catch(() => ({ error: r.status + " " + r.statusText }));
  if (!r.ok) throw new Error(data.error || (r.status + " " + r.statusText));
  return data;
}

function num(v, digits) { return v == null ? "?" : v.toFixed(digits); }
function showError(msg) { const e = $("error"); e.textContent = msg; e.hidden = !msg; }
function text(id, s) { $(id).textContent = s; }
function list(id, items) {
  const ul = $(id); ul.replaceChildren();
  for (const it of items || []) { const li = document.createElement("li"); li.textContent = it; ul.appendChild(li); }
}
function verdictClass(el, verdict) { el.className = "status verdict-" + (verdict || "none"); }
function setImg(id, name) { const im = $(id); if (name) { im.src = fileUrl(name); im.hidden = false; } else { im.hidden = true; } }

async function guarded(fn) {
  showError("");
  try { await fn(); } catch (e) { showError(e.message); }
}

// ---- state -----------------------------------------------------------------------------
async function refresh() {
  STATE = await api("api/state");
  render();
}

function render() {
  const s = STATE, st = s.state, d = s.devices;
  text("project-root", s.root);
  // devices
  const dl = $("devices-list"); dl.replaceChildren();
  for (const [k, v] of [["projector", d.projector], ["camera", d.camera]]) {
    const dt = document.createElement("dt"); dt.textContent = k; const dd = document.createElement("dd"); dd.textContent = v;
    dl.append(dt, dd);
  }
  for (const disp of d.displays || []) {
    const dd = document.createElement("dd"); dd.textContent = disp.label + (disp.projector ? "  <- the projector" : ""); dl.append(dd);
  }
  $("devices-virtual").hidden = !d.virtual;
  $("virtual-board").hidden = !d.virtual;
  if (d.virtual) {
    $("devices-projector-size").value = d.projector_size.join("x");
    const sel = $("virtual-pose");
    if (sel.options.length !== d.poses.length) {
      sel.replaceChildren(...d.poses.map((p, i) => { const o = document.createElement("option"); o.value = i; o.textContent = `pose ${i + 1} (${p.join(", ")} deg)`; return o; }));
    }
    sel.value = d.pose_index;
  }
  text("devices-status", d.virtual ? "virtual devices: the simulator plays projector, camera and board" : "");
  // board
  if (document.activeElement.tagName !== "INPUT") {
    $("board-cols").value = st.board.cols; $("board-rows").value = st.board.rows; $("board-square").value = st.board.square;
  }
  const boardDone = !!s.files.board;
  $("board-svg").hidden = !boardDone;
  if (boardDone) $("board-svg").href = fileUrl(s.files.board);
  text("board-status", boardDone ? `board ${st.board.cols}x${st.board.rows} inner corners, square ${st.board.square} ${st.unit}` : "give the board and press Use this board");
  // camera
  text("camera-status", st.camera_file ? `camera: ${st.camera_file}` + (s.photos.length ? ` (from ${s.photos.length} photo(s))` : "") : (s.photos.length ? `${s.photos.length} photo(s); the camera is not trusted yet` : "no camera file: the projector pose calibrates the camera too"));
  // pose
  const pose = st.pose;
  if (pose) {
    text("pose-verdict", `${pose.name}: ${pose.verdict}`); verdictClass($("pose-verdict"), pose.verdict);
    setImg("pose-check", s.pose_check);
  }
  // calibration
  if (s.calibration && !(st.calibration && !st.calibration.trusted)) showCalibration(s.calibration, !!s.files.calibration);
  renderExports(s.exports);
  renderRig(s);
  gate();
}

function rigOk(s) {  // a rig pose captured whole, every projector's verdict good or weak
  const r = s.rig;
  return !!(r && r.complete && r.projectors.every((n) => ["good", "weak"].includes((r.verdicts || {})[n])));
}

function thumbs(id, names, alt) {
  $(id).replaceChildren(...(names || []).map((n) => { const im = document.createElement("img"); im.src = fileUrl(n); im.alt = alt + " " + n; return im; }));
}

function renderRig(s) {
  const r = s.rig, st = s.state;
  if (!$("rig-projectors").value && s.devices.virtual) $("rig-projectors").placeholder = "left,right";
  if (r) {
    const words = r.projectors.map((n) => `${n} ${(r.verdicts || {})[n] || "?"}`).join(", ");
    text("rig-verdict", `${r.name}: ${words}` + (r.complete ? "" : " (not captured whole: capture the rig again)"));
    verdictClass($("rig-verdict"), rigOk(s) ? "good" : "degenerate");
    thumbs("rig-checks", r.checks, "the check picture of");
    thumbs("rig-blend-alpha", r.alpha, "the blend mask");
  }
  const latest = st.rig_calibration, written = !!s.files.rig_calibration && !(latest && !latest.trusted);
  if (latest && !$("rig-calibrate-verdict").textContent) text("rig-calibrate-verdict", `rig calibration: ${latest.verdict}` + (latest.trusted ? "" : " (not written)"));
  setImg("rig-figure", written && s.files.rig_figure ? s.files.rig_figure : null);
  const rep = $("rig-report"); rep.hidden = !(written && s.files.rig_report);
  if (!rep.hidden) rep.href = fileUrl(s.files.rig_report);
}

function fillTable(id, t) {
  const el = $(id); el.replaceChildren();
  const head = el.insertRow(); for (const h of t.header) { const th = document.createElement("th"); th.textContent = h; head.appendChild(th); }
  for (const r of t.rows) { const tr = el.insertRow(); for (const cell of r) tr.insertCell().textContent = cell; }
}

function showRigCalibration(c) {
  text("rig-calibrate-verdict", `rig calibration: ${c.verdict} - ${c.meaning}` + (c.written.length ? "" : " (not written: procam does not write a calibration it cannot trust)"));
  verdictClass($("rig-calibrate-verdict"), c.verdict);
  list("rig-calibrate-reasons", c.reasons);
  fillTable("rig-devices", c.device_table); fillTable("rig-relative", c.relative_table); fillTable("rig-agreement", c.agreement_table);
  $("rig-devices").createCaption().textContent = c.uncertainty;
}

function gate() {
  const s = STATE, st = s.state, busy = !!JOB;
  const boardDone = !!s.files.board;
  const poseOk = st.pose && (st.pose.verdict === "good" || st.pose.verdict === "weak");
  const latest = st.calibration;  // the latest attempt: an untrusted one is not written, and nothing goes on from it
  const calibOk = !!(s.calibration && s.calibration.trusted && s.files.calibration && (!latest || latest.trusted));
  for (const id of ["board-save", "devices-projector-size", "virtual-pose", "turn-left", "turn-right", "tilt-up",
                    "tilt-down"]) $(id).disabled = busy;
  for (const id of ["camera-photo", "camera-load", "camera-none", "pose-capture"]) $(id).disabled = busy || !boardDone;
  $("calibrate-run").disabled = busy || !poseOk;
  $("world-run").disabled = busy || !calibOk;
  $("export-run").disabled = busy || !calibOk;
  $("pose-cancel").disabled = !busy;
  $("rig-cancel").disabled = !busy;
  $("devices-exposure").disabled = busy || !boardDone;
  $("rig-capture").disabled = busy || !boardDone;
  $("rig-calibrate").disabled = busy || !rigOk(s);
  $("rig-blend").disabled = busy || !(s.rig && s.rig.complete);
  $("step-rig").classList.toggle("locked", !boardDone);
  for (const [id, ok] of [["step-camera", boardDone], ["step-pose", boardDone], ["step-calibrate", poseOk],
                          ["step-world", calibOk], ["step-export", calibOk]]) $(id).classList.toggle("locked", !ok);
}

function showCalibration(c, written) {
  text("calibrate-verdict", `verdict: ${c.verdict} - ${c.meaning}` + (written ? "" : " (not written: procam does not write a calibration it cannot trust)"));
  verdictClass($("calibrate-verdict"), c.verdict);
  list("calibrate-reasons", c.reasons);
  const t = $("calibrate-table"); t.replaceChildren();
  const head = t.insertRow(); for (const h of c.header) { const th = document.createElement("th"); th.textContent = h; head.appendChild(th); }
  for (const r of c.rows) { const tr = t.insertRow(); for (const cell of r) tr.insertCell().textContent = cell; }
  const cap = t.createCaption(); cap.textContent = c.plus_minus;
  list("calibrate-rests-on", (c.rests_on || []).map((l) => "projector: " + l));
  setImg("calibrate-residuals", written && STATE.files.residuals ? STATE.files.residuals : null);
  const rep = $("calibrate-report"); rep.hidden = !(written && STATE.files.report);
  if (!rep.hidden) rep.href = fileUrl(STATE.files.report);
}

function renderExports(files) {
  const ul = $("export-files"); ul.replaceChildren();
  const all = (files || []).slice();
  if (STATE.files.report) all.push(STATE.files.report);
  for (const f of all) {
    const li = document.createElement("li"); const a = document.createElement("a");
    a.href = fileUrl(f, true); a.textContent = f; a.setAttribute("download", f.split("/").pop());
    li.appendChild(a); ul.appendChild(li);
  }
}

// ---- jobs ------------------------------------------------------------------------------
async function runJob(path, progressId, onDone, body) {
  JOB = await api(path, body || {});
  gate();
  while (JOB && JOB.state === "running") {
    await new Promise((r) => setTimeout(r, 200));
    JOB = await api(`api/jobs/${JOB.id}`);
    text("job-line", `${JOB.kind}: ${JOB.message} (${JOB.done}/${JOB.total || "?"})`);
    if (progressId) { $(progressId).max = JOB.total || 1; $(progressId).value = JOB.done; }
  }
  const job = JOB; JOB = null;
  text("job-line", `${job.kind}: ${job.state} (${job.seconds} s)`);
  await refresh();
  if (job.state === "done") onDone(job.result);
  else showError(job.error || job.state);
}

// ---- the live view ---------------------------------------------------------------------
async function previewLoop() {
  let next = null;  // the next frame's request, in flight while this one is decoded and drawn
  const ask = () => { const r = api("api/preview"); r.catch(() => {}); return r; };
  for (;;) {
    if (!$("preview-live").checked || JOB || !STATE) { next = null; await new Promise((r) => setTimeout(r, 300)); continue; }
    try {
      const p = await (next || ask());
      next = p.busy ? null : ask();
      if (!p.busy) await drawPreview(p);
    } catch (e) { next = null; text("advice", e.message); await new Promise((r) => setTimeout(r, 1000)); }
    await new Promise((r) => requestAnimationFrame(r));  // the page shows each frame before the next is drawn
  }
}

function drawPreview(p) {
  return new Promise((resolve) => {
    const img = new Image();
    img.onload = () => {
      const cv = $("preview"), ctx = cv.getContext("2d");
      if (cv.width !== img.width) { cv.width = img.width; cv.height = img.height; }
      ctx.drawImage(img, 0, 0);
      const a = p.advice || { state: "none", message: "the advisor is looking at the first frame", actions: [] };
      if (a.error) { a.state = "none"; a.message = a.error; a.actions = []; }
      const colour = { ready: "#2e7d32", good: "#2e7d32", adjust: "#f9a825", "no-board": "#c62828" }[a.state] || "#888";
      if (a.corners) {
        ctx.fillStyle = colour;
        for (const [x, y] of a.corners) { ctx.beginPath(); ctx.arc(x, y, 4, 0, 2 * Math.PI); ctx.fill(); }
      }
      if (a.outline) {
        ctx.strokeStyle = colour; ctx.lineWidth = 4; ctx.beginPath();
        a.outline.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y))); ctx.closePath(); ctx.stroke();
      }
      const photos = STATE && STATE.state.photos;
      if (photos) {  // the camera step's coverage: where the board was in the photos so far
        ctx.fillStyle = "rgba(0,200,255,0.15)";
        for (const o of photos.outlines) { ctx.beginPath(); o.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y))); ctx.closePath(); ctx.fill(); }
      }
      if (a.outline) drawMoves(ctx, a, colour);
      const lines = a.lines || [{ style: "head", text: a.message }];
      const px = Math.round(cv.width / 40);
      ctx.fillStyle = "rgba(0,0,0,0.65)"; ctx.fillRect(0, 0, cv.width, 1.4 * px * lines.length + px / 2);
      lines.forEach((l, i) => {
        ctx.font = `${l.style === "head" ? Math.round(1.2 * px) : px}px sans-serif`;
        ctx.fillStyle = l.style === "head" ? colour : "#fff"; ctx.fillText(l.text, px / 2, 1.2 * px + 1.4 * px * i);
      });
      const cam = a.camera ? ` camera f ± ${fmtPct(a.camera)}` : "", proj = a.projector ? `, projector f ± ${fmtPct(a.projector)}` : "";
      text("advice", `${a.state}: ${a.message}${cam}${proj}`);
      $("camera-view").dataset.state = a.state;
      const now = performance.now(); frames.push(now); frames = frames.filter((t) => now - t < 2000);
      text("preview-fps", `${(frames.length / 2).toFixed(1)} frames/s`);
      DRAWN.frames += 1;  // counted for scripts and benchmarks: frames drawn, and the advice of distinct frames
      if (a.of_frame != null && a.of_frame !== DRAWN.lastAdvice) { DRAWN.advice += 1; DRAWN.lastAdvice = a.of_frame; }
      $("preview-fps").dataset.frames = DRAWN.frames; $("preview-fps").dataset.advice = DRAWN.advice;
      resolve();
    };
    img.onerror = () => resolve();
    img.src = p.image;
  });
}
// the advisor's next move on the picture, as procam advise's window draws it: turn / tilt an arrow from the board's
// centre to the edge that goes away, move an arrow the way to move
function drawMoves(ctx, a, colour) {
  const o = a.outline, mid = (p, q) => [(p[0] + q[0]) / 2, (p[1] + q[1]) / 2];
  const c = o.reduce(([x, y], [u, v]) => [x + u / o.length, y + v / o.length], [0, 0]);
  const side = { left: mid(o[0], o[3]), right: mid(o[1], o[2]), top: mid(o[0], o[1]), bottom: mid(o[2], o[3]) };
  const w = ctx.canvas.width, step = 0.25 * Math.min(w, ctx.canvas.height);
  for (const act of a.actions) {
    let end = null, label = "", col = "#00c8ff";
    if ((act.kind === "turn" || act.kind === "tilt") && act.degrees) {
      const s = act.kind === "turn" ? (act.degrees > 0 ? "right" : "left") : (act.degrees > 0 ? "top" : "bottom");
      end = side[s]; label = `${act.kind} ~${Math.abs(act.degrees).toFixed(0)} deg: ${s} edge away`;
    } else if (act.kind === "move" && act.direction) {
      const v = { left: [-1, 0], right: [1, 0], up: [0, -1], down: [0, 1] }[act.direction];
      end = [c[0] + step * v[0], c[1] + step * v[1]]; col = colour;
    }
    if (!end) continue;
    const d = [end[0] - c[0], end[1] - c[1]], n = Math.hypot(d[0], d[1]) || 1, u = [d[0] / n, d[1] / n];
    const h = w / 60;
    ctx.strokeStyle = col; ctx.fillStyle = col; ctx.lineWidth = w / 250;
    ctx.beginPath(); ctx.moveTo(c[0], c[1]); ctx.lineTo(end[0], end[1]); ctx.stroke();
    ctx.beginPath(); ctx.moveTo(end[0] + u[0] * h, end[1] + u[1] * h); ctx.lineTo(end[0] - u[1] * h, end[1] + u[0] * h);
    ctx.lineTo(end[0] + u[1] * h, end[1] - u[0] * h); ctx.closePath(); ctx.fill();
    if (label) { ctx.font = `${Math.round(w / 45)}px sans-serif`; ctx.fillText(label, Math.min(end[0], w - ctx.measureText(label).width), end[1] + w / 30); }
  }
}
function fmtPct(dev) { return dev.rel_std_f_pct == null ? "?" : dev.rel_std_f_pct.toFixed(2) + " %"; }

// ---- the controls ----------------------------------------------------------------------
function wire() {
  $("board-save").onclick = () => guarded(async () => {
    await api("api/board", { cols: parseInt($("board-cols").value, 10), rows: parseInt($("board-rows").value, 10),
                             square: parseFloat($("board-square").value) });
    await refresh();
  });
  $("devices-projector-size").onchange = () => guarded(async () => {
    await api("api/devices", { projector_size: $("devices-projector-size").value.split("x").map(Number) }); await refresh();
  });
  $("virtual-pose").onchange = () => guarded(async () => { await api("api/devices", { pose: parseInt($("virtual-pose").value, 10) }); });
  for (const [id, move] of [["turn-left", { turn: -5 }], ["turn-right", { turn: 5 }], ["tilt-up", { tilt: 5 }], ["tilt-down", { tilt: -5 }]])
    $(id).onclick = () => guarded(async () => { await api("api/devices", move); });
  $("camera-photo").onclick = () => guarded(() => runJob("api/camera", null, (r) => {
    const pm = r.f_std == null ? "" : ` ± ${num(r.f_std, 1)}`;
    text("camera-status", `${r.photos.length} photo(s): f_c = ${num(r.f, 1)}${pm} px, ${r.verdict}, ` +
      `${Math.round(100 * r.coverage)} % of the image covered` +
      (r.enough ? " - enough" : " - take another photo, the board turned another way") +
      (r.reasons.length ? ` (${r.reasons.join("; ")})` : ""));
  }, { action: "photo" }));
  $("camera-load").onclick = () => guarded(async () => { await api("api/camera", { action: "file", name: $("camera-file").value }); await refresh(); });
  $("camera-none").onclick = () => guarded(async () => { await api("api/camera", { action: "none" }); await refresh(); });
  $("pose-capture").onclick = () => guarded(() => runJob("api/capture", "pose-progress", (r) => {
    text("pose-verdict", `${r.pose}: ${r.verdict}`); verdictClass($("pose-verdict"), r.verdict);
    list("pose-lines", r.lines); setImg("pose-check", r.check);
  }));
  $("pose-cancel").onclick = () => guarded(async () => { if (JOB) await api(`api/jobs/${JOB.id}/cancel`, {}); });
  $("rig-cancel").onclick = $("pose-cancel").onclick;
  $("devices-exposure").onclick = () => guarded(() => runJob("api/exposure", null, (r) => {
    text("devices-exposure-verdict", r.ok ? "the exposure is fine for a capture" + (r.lines.length > 1 ? ", with advice:" : "") : "a capture would refuse: " + r.reason);
    verdictClass($("devices-exposure-verdict"), r.ok ? (r.lines.length > 1 ? "weak" : "good") : "failed");
    list("devices-exposure-lines", r.lines);
  }));
  $("rig-capture").onclick = () => guarded(() => runJob("api/rig/capture", "rig-progress", (r) => {
    list("rig-lines", r.lines);
  }, { projectors: $("rig-projectors").value.trim() || null }));
  $("rig-calibrate").onclick = () => guarded(() => runJob("api/rig/calibrate", "rig-progress", showRigCalibration));
  $("rig-blend").onclick = () => guarded(() => runJob("api/rig/blend", "rig-progress", (r) => {
    text("rig-blend-status", "blend masks in blend/: " + Object.entries(r.overlap).map(([n, f]) => `${n} overlaps on ${Math.round(100 * f)} % of its pixels`).join(", "));
  }));
  $("calibrate-run").onclick = () => guarded(() => runJob("api/calibrate", "calibrate-progress", (r) => showCalibration(r, r.written.length > 0)));
  $("world-run").onclick = () => guarded(() => runJob("api/world", null, (r) => {
    text("world-verdict", `${r.verdict}: ${r.found} of ${r.targets} spots found, miss ${num(r.rms_px, 3)} px RMS (${num(r.max_px, 3)} max); ${r.reasons.join("; ")}` + (r.diagnosis ? `; ${r.diagnosis}` : ""));
    verdictClass($("world-verdict"), r.verdict === "holds" ? "good" : "degenerate"); setImg("world-picture", r.picture);
  }));
  $("export-run").onclick = () => guarded(async () => {
    const formats = [...document.querySelectorAll("#export-formats input:checked")].map((x) => x.value);
    await runJob("api/export", null, () => {}, { formats, near: parseFloat($("export-near").value), far: parseFloat($("export-far").value) });
  });
}

window.addEventListener("DOMContentLoaded", () => { wire(); guarded(refresh); previewLoop(); });
