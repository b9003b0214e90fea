// Runs the viewer page's script under Node with a minimal fake DOM (no drawing: the canvas context accepts
// every call) and prints <pre id="check" data-status="...">...</pre> as a browser's --dump-dom would, so
// test_viewer_chromium can check the page's projection and grid layout where no Chromium is installed.
// With a query ("?va=0.3,-0.2") it is the page's location.search; with events ("mousedown:X,Y;keydown:ArrowUp",
// X and Y in the dial's CSS pixels) they are sent in turn to the page's V/A dial after the script ran, and the
// dial's pick (data-pick) is printed too.
// Usage: node viewer_fake_dom.js view.html [QUERY [EVENTS]]
"use strict";
const fs = require("fs");
const html = fs.readFileSync(process.argv[2], "utf8");
const data = html.match(/<script type="application\/json" id="data">([\s\S]*?)<\/script>/)[1];
const code = html.match(/<script>([\s\S]*?)<\/script>/)[1];
const ctx = new Proxy({}, {
  get: (t, k) => (k === "measureText" ? () => ({width: 10}) : k === "getImageData" ? (x, y, w, h) => ({data: new Uint8Array(4 * w * h).fill(255)})
                  : k in t ? t[k] : () => {}),
  set: (t, k, v) => { t[k] = v; return true; },
});
const els = {};
function el(id) {
  if (!els[id]) els[id] = {id, textContent: id === "data" ? data : "", style: {}, value: 0, attrs: {},
    on: {}, setAttribute(k, v) { this.attrs[k] = v; }, addEventListener(k, f) { (this.on[k] = this.on[k] || []).push(f); }, getContext() { return ctx; },
    getBoundingClientRect() { return {left: 0, top: 0}; }};
  return els[id];
}
global.document = {getElementById: el, addEventListener() {}, title: ""};
global.window = {devicePixelRatio: 1, addEventListener() {}};
if (process.argv[3]) global.location = {search: process.argv[3]};
let frames = 0;
global.requestAnimationFrame = f => { if (frames++ < 3) setTimeout(() => f(frames * 100), 0); };
try {
  new Function(code)();
  for (const ev of (process.argv[4] || "").split(";").filter(Boolean)) {
    const [type, arg] = ev.split(":"), xy = arg.split(",").map(Number);
    const e = type === "keydown" ? {key: arg, preventDefault() {}} : {clientX: xy[0], clientY: xy[1], preventDefault() {}};
    for (const f of el("dial").on[type] || []) f(e);
  }
} catch (e) { el("check").attrs["data-status"] = "error: " + e; }
setTimeout(() => {
  const c = el("check");
  process.stdout.write('<pre id="check" data-status="' + c.attrs["data-status"] + '" data-pick="' + (c.attrs["data-pick"] || "") + '">' +
                       c.textContent + "</pre>\n");
}, 50);
