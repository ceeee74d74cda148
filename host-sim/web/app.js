// The live map: draws the state the server pushes (server-sent events "state"); it computes
// nothing itself.
"use strict";

const map = L.map("map", { preferCanvas: true, zoomSnap: 0.25 }).setView([0, 0], 2);
const layers = L.layerGroup().addTo(map);
let fitted = false;

fetch("/config.json").then((r) => r.json()).then((c) => {
  if (c && c.tiles) {
    L.tileLayer(c.tiles, { maxZoom: 19, attribution: "tiles: see --tiles" }).addTo(map);
  }
});
fetch("/roads.geojson").then((r) => r.json()).then((g) => {
  if (g) {
    L.geoJSON(g, { style: { color: "#888", weight: 1.5 }, interactive: false }).addTo(map);
  }
});

function text(id, html, attrs) {
  const el = document.getElementById(id);
  el.innerHTML = html;
  for (const [k, v] of Object.entries(attrs || {})) el.setAttribute(k, v);
}

function fmt(x, d) { return Number(x).toFixed(d); }

function drawHistory(h) {
  const svg = document.getElementById("history");
  if (!h.length) { svg.innerHTML = ""; return; }
  const w = 300, ht = 120, pad = 34;
  const n = h[h.length - 1][0] || 1;
  const lo = 1, hi = 4; // log10 of 10 m .. 10 km
  const x = (b) => pad + (w - pad - 4) * b / n;
  const y = (c) => {
    const l = Math.min(hi, Math.max(lo, Math.log10(Math.max(c, 1))));
    return 4 + (ht - pad) * (hi - l) / (hi - lo);
  };
  let s = "";
  for (const c of [10, 100, 1000, 10000]) {
    s += `<line x1="${pad}" x2="${w}" y1="${y(c)}" y2="${y(c)}" stroke="#ddd"/>`;
    s += `<text x="${pad - 3}" y="${y(c) + 3}" font-size="9" text-anchor="end">${c}</text>`;
  }
  const pts = h.map((p) => `${fmt(x(p[0]), 1)},${fmt(y(p[1]), 1)}`).join(" ");
  s += `<polyline fill="none" stroke="#d62728" stroke-width="1.5" points="${pts}"/>`;
  s += `<text x="${w / 2}" y="${ht - 4}" font-size="9" text-anchor="middle">bearings (${n}); CEP50 m, log</text>`;
  svg.innerHTML = s;
}

// The DF unit's own fix ($PFOXF), as the unit said it: a diamond (the host's emitters are
// discs) with its 95 % ellipse dotted, and its numbers in the panel.
function drawUnit(u, bounds) {
  if (!u) { text("unit", "none in the input", { "data-unit": "0" }); return; }
  if (u.at) {
    if (u.ellipse.length) {
      L.polygon(u.ellipse, { color: "#17becf", weight: 2, dashArray: "2 4", fillOpacity: 0.08 }).addTo(layers);
    }
    const icon = L.divIcon({ className: "unit-fix", html: "<div></div>", iconSize: [14, 14] });
    L.marker(u.at, { icon, keyboard: false }).addTo(layers).bindTooltip("the DF unit's own fix");
    bounds.extend(u.at);
  }
  const where = u.at
    ? `${fmt(u.at[0], 5)}, ${fmt(u.at[1], 5)}<br>CEP50 <b>${fmt(u.cep50_m, 1)} m</b>, 95 % ellipse `
      + `${fmt(u.major_m, 0)} × ${fmt(u.minor_m, 0)} m at ${fmt(u.orientation_deg, 0)}°`
    : "no position";
  const when = u.time ? `<br>at ${u.time} UTC (${u.status_text})` : "";
  const used = u.used !== null ? `; ${u.used} of ${u.window} bearings, sigma ${fmt(u.sigma_deg, 2)}°` : "";
  const lost = u.latest_status ? `<br><span class="why">latest status ${u.latest_status}</span>` : "";
  const health = u.rejected !== null ? `<br><small>unit rejected ${u.rejected} records, lost ${u.lost_bytes} bytes</small>` : "";
  const bad = u.malformed ? `<br><small class="why">${u.malformed} unit sentences malformed (ignored)</small>` : "";
  text("unit", `<div class="unit">DF unit: ${where}${when}${used}${lost}${health}${bad}</div>`
    + `<small>${u.fixes} fix sentences</small>`, {
    "data-unit": "1",
    "data-cep50": u.at ? fmt(u.cep50_m, 1) : "",
    "data-status": u.status || "",
    "data-malformed": u.malformed,
  });
}

function render(st) {
  layers.clearLayers();
  text("status", `update ${st.update}, ${st.bearings} bearings${st.done ? ", input ended" : ""}`);
  if (st.route.length) L.polyline(st.route, { color: "#1f77b4", weight: 3 }).addTo(layers);
  for (const r of st.rays) L.polyline(r, { color: "#ff7f0e", weight: 1, opacity: 0.5 }).addTo(layers);
  const bounds = L.latLngBounds(st.route.length ? st.route : []);
  // Every DF station: fixed ones as squares, each with its latest line of bearing and offset.
  for (const s of st.stations || []) {
    L.polyline(s.ray, { color: "#8c564b", weight: 1.5, opacity: 0.8 }).addTo(layers);
    const tip = `${s.id} (${s.fixed ? "fixed" : "mobile"}): offset ${fmt(s.offset_deg[0], 1)} ± `
      + `${fmt(s.offset_deg[1], 1)}° (${s.offset_from}), ${s.bearings} bearings`
      + (s.direction_found_deg ? `; an error that follows the direction found: `
        + `${fmt(s.direction_found_deg[0], 1)}° and ${fmt(s.direction_found_deg[1], 1)}° harmonics` : "");
    if (s.fixed) {
      const icon = L.divIcon({ className: "station-fixed", html: "<div></div>", iconSize: [12, 12] });
      L.marker(s.at, { icon, keyboard: false, title: s.id }).addTo(layers).bindTooltip(tip);
    } else {
      L.circleMarker(s.at, { radius: 4, color: "#8c564b", fillOpacity: 1 }).addTo(layers).bindTooltip(tip);
    }
    bounds.extend(s.at);
  }
  let fix = "";
  const verdicts = (st.advice && st.advice.emitters) || [];
  const served = (st.advice && st.advice.for_emitters) || [];
  st.emitters.forEach((e, i) => {
    // The emitters the move is for are drawn heavier; each says its own verdict.
    const v = verdicts[i];
    const isFor = served.includes(i + 1);
    L.polygon(e.ellipse, { color: "#d62728", weight: isFor ? 3 : 1.5, fillOpacity: 0.1 }).addTo(layers);
    L.circleMarker(e.at, { radius: 6, color: "#d62728", fillOpacity: 1 }).addTo(layers)
      .bindTooltip(`emitter ${i + 1}${isFor ? " (the move is for it)" : ""}`);
    bounds.extend(e.at);
    const verdict = !v ? ""
      : v.good_enough ? `<br><span class="good">good enough</span>`
      : `<br><span class="why">${v.reason_text}</span> <small>(missing: ${v.missing.join(", ")})</small>`;
    fix += `<div class="emitter" data-emitter="${i + 1}" data-good="${v ? v.good_enough : ""}">`
      + `Emitter ${i + 1}${e.freq_mhz ? ` (${fmt(e.freq_mhz, 3)} MHz)` : ""}: `
      + `${fmt(e.at[0], 5)}, ${fmt(e.at[1], 5)}<br>CEP50 <b>${fmt(e.cep50_m, 0)} m</b>, `
      + `${fmt(100 * e.confidence, 0)} % ellipse; ${e.used} bearings`
      + `${e.consistent ? "" : ", <span class=why>inconsistent</span>"}; `
      + `offset ${fmt(e.offset_deg[0], 1)} ± ${fmt(e.offset_deg[1], 1)}°${verdict}</div>`;
  });
  st.others.forEach((o, i) => {
    L.polygon(o.ellipse, { color: "#9467bd", weight: 1.5, dashArray: "4 3", fillOpacity: 0.05 }).addTo(layers);
    L.circleMarker(o.at, { radius: 4, color: "#9467bd", fillOpacity: 1 }).addTo(layers);
    fix += `<div class="other">Other source ${i + 1}: ${fmt(o.at[0], 5)}, ${fmt(o.at[1], 5)}, `
      + `CEP50 ${fmt(o.cep50_m, 0)} m, ${o.used} bearings</div>`;
  });
  // Open ranges: the observers' line of bearing as a dashed wedge, its figures in the panel.
  (st.regions || []).forEach((r, i) => {
    L.polygon(r.wedge, { color: "#ff7f0e", weight: 2, dashArray: "6 4", fillOpacity: 0.08 }).addTo(layers);
    L.circleMarker([r.lat, r.lon], { radius: 4, color: "#ff7f0e", fillOpacity: 1 }).addTo(layers)
      .bindTooltip(`region ${i + 1}: the line of bearing`);
    const to = r.max_range_m == null ? "unbounded" : `${fmt(r.max_range_m / 1000, 1)} km`;
    fix += `<div class="region" data-region="${i + 1}" data-parallel="${r.parallel}">`
      + `Region${r.freq_mhz ? ` (${fmt(r.freq_mhz, 3)} MHz)` : ""}: bearing `
      + `<b>${fmt(r.bearing_deg, 1)}° ± ${fmt(r.half_width_deg, 1)}°</b> from `
      + `${fmt(r.lat, 5)}, ${fmt(r.lon, 5)}, range ${fmt(r.min_range_m / 1000, 1)} km to ${to}`
      + `<br><span class="why">${r.line}</span></div>`;
  });
  // Emitters that move: the track so far, the current ellipse and where the velocity leads
  // in a minute.
  (st.tracks || []).forEach((t, i) => {
    L.polyline(t.line, { color: "#e377c2", weight: 3 }).addTo(layers);
    if (t.ellipse.length) L.polygon(t.ellipse, { color: "#e377c2", weight: 1.5, fillOpacity: 0.1 }).addTo(layers);
    L.polyline(t.arrow, { color: "#e377c2", weight: 4, dashArray: "2 4" }).addTo(layers);
    L.circleMarker(t.arrow[1], { radius: 3, color: "#e377c2", fillOpacity: 1 }).addTo(layers)
      .bindTooltip("where the velocity leads in a minute");
    L.circleMarker(t.at, { radius: 6, color: "#e377c2", fillOpacity: 1 }).addTo(layers)
      .bindTooltip(`moving emitter ${i + 1}`);
    bounds.extend(t.at);
    fix += `<div class="track" data-track="${i + 1}" data-speed="${fmt(t.speed_mps, 1)}" `
      + `data-points="${t.line.length}">Moving emitter${t.freq_mhz ? ` (${fmt(t.freq_mhz, 3)} MHz)` : ""}: `
      + `${fmt(t.at[0], 5)}, ${fmt(t.at[1], 5)}<br><b>${fmt(t.speed_mps, 1)} m/s</b> toward `
      + `${fmt(t.heading_deg, 0)}°, P(moving) ${fmt(t.p_moving, 2)}</div>`;
  });
  text("fix", fix || (st.fix_error || "no fix yet"),
    { "data-emitters": st.emitters.length, "data-tracks": (st.tracks || []).length });
  drawUnit(st.unit, bounds);
  const a = st.advice;
  if (a) {
    const path = a.turn_ll ? [a.vehicle_ll, a.turn_ll, a.waypoint_ll] : [a.vehicle_ll, a.waypoint_ll];
    L.polyline(path, { color: "#2ca02c", weight: 5, dashArray: "8 6" }).addTo(layers);
    L.circleMarker(a.waypoint_ll, { radius: 5, color: "#2ca02c", fillOpacity: 1 }).addTo(layers);
    if (a.turn_ll) L.circleMarker(a.turn_ll, { radius: 7, color: "#2ca02c", fill: false }).addTo(layers);
    bounds.extend(a.waypoint_ll);
    const several = (a.emitters || []).length > 1;
    const names = (a.for_emitters || []).join(", ");
    const plural = (a.for_emitters || []).length > 1 ? "s" : "";
    const verdict = a.good_enough
      ? `<div class="good">Good enough: stop${several ? " (every emitter)" : ""}</div>`
      : (several ? `<div class="for">for emitter${plural} ${names}</div>` : "")
        + `<div class="why">${a.reason_text}</div><small>missing: ${a.missing.join(", ")}</small><br>`;
    text("advice", `<div class="move">${a.line}</div>${verdict}`
      + `<small>predicted CEP50 in ${a.on_roads ? "road" : "free-heading"} plan: ${fmt(a.predicted_cep50_m, 0)} m</small>`,
      { "data-reason": a.reason, "data-heading": fmt(a.heading_deg, 0), "data-for": names });
  } else {
    text("advice", st.advice_error || "none yet");
  }
  drawHistory(st.history);
  if (!fitted && bounds.isValid()) {
    map.fitBounds(bounds.pad(0.15));
    fitted = true;
  }
}

fetch("/state").then((r) => r.json()).then(render);
const source = new EventSource("/events");
source.addEventListener("state", (ev) => render(JSON.parse(ev.data)));
source.addEventListener("end", () => {
  // The input has ended: no more states will come, and reconnecting would only ask again.
  source.close();
  document.body.dataset.ended = "1";
});
