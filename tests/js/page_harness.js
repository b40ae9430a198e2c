// Runs the script of an iqc html page in node against a minimal DOM and a recording WebGL2 stub (no
// browser needed): checks what the page builds and what it sends to WebGL. Usage:
//   node page_harness.js PAGE.html  → prints one JSON line: title, sliders, uniforms set per frame, errors.
"use strict";
const fs = require("fs");
const vm = require("vm");
const html = fs.readFileSync(process.argv[2], "utf8");
const scripts = [...html.matchAll(/<script([^>]*)>([\s\S]*?)<\/script>/g)];
const byId = {};
class Element {
  constructor(tag) { this.tag = tag; this.children = []; this.listeners = {}; this.dataset = {}; this.style = {};
                     this.attributes = {}; this._text = ""; this.clientWidth = 64; this.clientHeight = 36; }
  appendChild(c) { this.children.push(c); c.parent = this; return c; }
  addEventListener(k, f) { (this.listeners[k] = this.listeners[k] || []).push(f); }
  setAttribute(k, v) { this.attributes[k] = String(v); }
  set textContent(v) { this._text = String(v); this.children = []; }
  get textContent() { return this._text + this.children.map(c => c.textContent).join(""); }
  set innerHTML(v) { throw new Error("innerHTML used"); }
  getBoundingClientRect() { return { left: 0, top: 0, right: 64, bottom: 36, width: 64, height: 36 }; }
  fire(k, e) { for (const f of this.listeners[k] || []) f(e || {}); }
  getContext() { return gl; }
}
const calls = [];
let frameCalls = [];
const gl = new Proxy({}, {
  get(_, name) {
    if (/^[A-Z_0-9]+$/.test(name)) return name;
    if (name === "getShaderParameter" || name === "getProgramParameter") return () => true;
    if (name === "getUniformLocation") return (p, n) => ({ name: n });
    return (...args) => {
      if (String(name).startsWith("uniform"))  // uniformMatrix*: (location, transpose, values)
        frameCalls.push([args[0] && args[0].name, Array.from(args.slice(String(name).startsWith("uniformMatrix") ? 2 : 1)).flat()]);
      if (name === "drawArrays") { calls.push(frameCalls); frameCalls = []; }
      if (name === "shaderSource") calls.sources = (calls.sources || []).concat([args[1]]);
      return {};
    };
  }
});
for (const m of scripts) {
  const id = (m[1].match(/id="([^"]+)"/) || [])[1];
  if (id) { const e = new Element("script"); e.textContent = m[2]; byId[id] = e; }
}
const document = {
  title: "",
  getElementById(id) { return byId[id] || (byId[id] = new Element(id === "canvas" ? "canvas" : "div")); },
  createElement(tag) { return new Element(tag); },
};
const rafQueue = [];
const storage = {};
const sandbox = {
  document, window: { addEventListener() {} }, console, JSON, Math, Number, String, Array, Object, isFinite, Error,
  performance: { now: () => 0 }, devicePixelRatio: 1,
  requestAnimationFrame: f => rafQueue.push(f),
  sessionStorage: { getItem: k => storage[k] || null, setItem: (k, v) => { storage[k] = v; } },
};
sandbox.window.document = document;
const inline = scripts.filter(m => !/type=/.test(m[1]));
if (inline.length !== 1) throw new Error("expected one inline script, found " + inline.length);
vm.runInNewContext(inline[0][2], sandbox);
const step = t => { const f = rafQueue.shift(); if (f) f(t); };
step(16);
const sliders = [], colours = [], intensities = [];
const walk = e => {
  if (e.tag === "input" && e.type === "range") (e.dataset.intensity ? intensities : sliders).push(e);
  if (e.tag === "input" && e.type === "color") colours.push(e);
  e.children.forEach(walk);
};
walk(byId.params);
// Move the first slider to its maximum and draw again: the next frame must send the new value.
let moved = null;
if (sliders.length) {
  const s = sliders[0];
  s.value = s.max;
  s.fire("input");
  step(32);
  moved = { uniform: s.dataset.uniform, component: Number(s.dataset.component), max: Number(s.max) };
}
// Pick mid grey in the first colour picker: the next frame sends what the page makes of it.
let picked = null;
if (colours.length) {
  const c = colours[0];
  c.value = "#808080";
  c.fire("input");
  step(48);
  const frame = calls[calls.length - 1] || [];
  picked = { key: c.dataset.colour, frame };
}
const labels = [];
const walkLabels = e => { if (e.tag === "label" || e.tag === "summary" || e.tag === "legend") labels.push(e.textContent); e.children.forEach(walkLabels); };
walkLabels(byId.params);
console.log(JSON.stringify({
  title: document.title, heading: byId.title.textContent, error: sandbox.window.iqcError || byId.error.textContent || null,
  picked, sliders: sliders.length, colours: colours.length, intensities: intensities.length, frames: calls.length, first: calls[0] || [], last: calls[calls.length - 1] || [], moved, labels,
  fragment_shader_chars: (calls.sources || [""])[1] ? calls.sources[1].length : 0,
}));
