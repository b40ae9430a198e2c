// Browser tests (run by ctest): Debian's chromium, headless with SwiftShader WebGL2, driven by
// playwright-core. Usage: node page.test.mjs IQC_BINARY SOURCE_DIR [PART...]
// PART (default: all) is one or more of examples (1), instances (3b), threejs (3), pages (2, 4 and the static
// scene): ctest runs each part as its own test, so two cores share them and none waits on another's timeout.
//  1. every example's --target html page loads offline with no console error and draws a non-blank
//     picture; moving a slider changes the picture;
//  2. a hostile title is shown as text (no dialog opens, the heading reads the title);
//  3. three.js, given the --target threejs module, draws the same picture as the html page, with plain
//     uniforms and the data texture (many instances); a raymarched sphere and three.js meshes occlude each other;
//  3b. pages of 100 and 400 rings fill their uniform blocks and data texture, and those sliders work;
//  4. under `iqc serve`, editing an included module updates the page, sliders keep their values.
import { chromium } from "playwright-core";
import { execFileSync, spawn } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";

const [iqc, src, ...partArgs] = process.argv.slice(2);
const parts = new Set(partArgs.length ? partArgs : ["examples", "instances", "threejs", "pages"]);
for (const p of parts)
  if (!["examples", "instances", "threejs", "pages"].includes(p)) { console.error(`unknown part '${p}'`); process.exit(2); }
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), "iqc-browser-"));
// Removed at exit (IQC_KEEP_TEST_FILES=1 keeps it, to look at): every run left one behind.
process.on("exit", () => { if (!process.env.IQC_KEEP_TEST_FILES) fs.rmSync(tmp, { recursive: true, force: true }); });
let failures = 0, checks = 0;
const check = (ok, what) => { console.log((ok ? "ok   " : "FAIL ") + what); checks++; if (!ok) failures++; };

const browser = await chromium.launch({
  executablePath: process.env.IQC_CHROMIUM || "/usr/bin/chromium",
  args: ["--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"],
});

// A digest of the canvas: the mean of its pixels and how many distinct colours it has.
async function picture(page) {
  return page.evaluate(() => {
    const c = document.getElementById("canvas");
    const gl = c.getContext("webgl2");
    const px = new Uint8Array(c.width * c.height * 4);
    gl.readPixels(0, 0, c.width, c.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let sum = 0; const colours = new Set();
    for (let i = 0; i < px.length; i += 4) { sum += px[i] + px[i + 1] + px[i + 2]; colours.add((px[i] << 16) | (px[i + 1] << 8) | px[i + 2]); }
    return { mean: sum / (px.length / 4 * 3), colours: colours.size, data: Array.from(px.filter((_, i) => i % 97 === 0)) };
  });
}
// Polls with evaluate (not waitForFunction, which some playwright versions run through eval: the page's CSP forbids it).
async function waitFor(page, fn, arg, ms = 60000) {
  const end = Date.now() + ms;
  while (Date.now() < end) {
    if (await page.evaluate(fn, arg)) return;
    await new Promise(r => setTimeout(r, 20));
  }
  throw new Error("timed out waiting for " + fn);
}
const differs = (a, b) => a.data.some((v, i) => Math.abs(v - b.data[i]) > 2);

async function open(url, viewport = { width: 480, height: 270 }) {
  const page = await browser.newPage({ viewport });
  const errors = [];
  page.on("console", m => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", e => errors.push(String(e)));
  page.on("dialog", d => { errors.push("dialog: " + d.message()); d.dismiss(); });
  const requests = [];
  page.on("request", r => requests.push(r.url()));
  await page.goto(url);
  await waitFor(page, () => window.iqcFrames > 0 || window.iqcError);
  return { page, errors, requests };
}

async function moveSlider(page, k) {
  const before = await picture(page);
  const frames = await page.evaluate(() => window.iqcFrames);
  await page.evaluate(k => {
    const s = document.querySelectorAll("#params input[type=range]")[k];
    s.value = s.value === s.max ? s.min : s.max;
    s.dispatchEvent(new Event("input"));
  }, k);
  await waitFor(page, n => window.iqcFrames > n, frames);
  return { before, after: await picture(page) };
}

const examples = parts.has("examples") ? fs.readdirSync(path.join(src, "examples")).filter(f => /\.(md|iq)$/.test(f)).sort() : [];
for (const name of examples) {
  const out = path.join(tmp, name + ".html");
  execFileSync(iqc, [path.join(src, "examples", name), "--target", "html", "-o", out], { stdio: "pipe" });
  const { page, errors, requests } = await open("file://" + out);
  check(errors.length === 0, `${name}: no console errors ${errors.join(" | ")}`);
  check(requests.every(u => u.startsWith("file://")), `${name}: nothing fetched from the network`);
  // Pause (time-dependent scenes hold still), then move sliders until one changes the picture (some, like a
  // light far outside the view, need not).
  await page.evaluate(() => document.getElementById("play").click());
  let before, after, k = 0;
  do { ({ before, after } = await moveSlider(page, k)); } while (!differs(before, after) && ++k < 6);
  check(before.colours > 10 && before.mean > 1, `${name}: the canvas is not blank (${before.colours} colours)`);
  check(differs(before, after), `${name}: moving a slider changes the picture`);
  await page.close();
}

// A static scene draws only when something changes (its --meta lists no iTime), and its frame-time readout is
// honest: at least a quarter of a frame's wall time measured by reading pixels back (it said 0.2 ms for ~1 s).
if (parts.has("pages")) {
  const out = path.join(tmp, "static.html");
  execFileSync(iqc, [path.join(src, "examples", "menger.iq"), "--target", "html", "-o", out], { stdio: "pipe" });
  const { page, errors } = await open("file://" + out);
  await new Promise(r => setTimeout(r, 500));
  const idle0 = await page.evaluate(() => window.iqcFrames);
  await new Promise(r => setTimeout(r, 1000));
  const idle1 = await page.evaluate(() => window.iqcFrames);
  check(idle1 === idle0 && idle0 <= 3, `static scene: no redraw loop (${idle0} frames, then ${idle1 - idle0} in a second)`);
  const wall = await page.evaluate(async () => {
    const c = document.getElementById("canvas"), gl = c.getContext("webgl2");
    const s = document.querySelectorAll("#params input[type=range]")[0];
    const n = window.iqcFrames, t0 = performance.now();
    s.value = s.value === s.max ? s.min : s.max;
    s.dispatchEvent(new Event("input"));
    while (window.iqcFrames === n) await new Promise(r => requestAnimationFrame(r));
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));  // waits for the draw
    const wall = performance.now() - t0;
    await new Promise(r => requestAnimationFrame(r));
    await new Promise(r => requestAnimationFrame(r));
    return wall;
  });
  const text = await page.evaluate(() => document.getElementById("fps").textContent);
  const ms = parseFloat(text);
  check(/ms\/frame \((GPU|frame to frame)\)/.test(text) && ms >= 0.25 * wall,
        `static scene: the frame time readout "${text}" is at least a quarter of a frame's wall time (${wall.toFixed(1)} ms)`);
  check(errors.length === 0, `static scene: no console errors ${errors.join(" | ")}`);
  await page.close();
}

// Many instances: per-instance data in uniform blocks (100 tilted rings) and in the data texture (400: their
// matrices alone pass one block's 16 KiB):
// the page fills them from --meta, draws them, and their sliders (written into the block or texture) change
// the picture.
function ringsScene(n) {
  let s = 'title = "rings"\n[modules]\nring = """\nshape\nD = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³\n' +
    't ∈ [0,2]x[0,2] default = (0.3, 0.08)\n"""\nground = """\nshape\nD = p_2 + 1\nwhere\np ∈ ℝ³\n"""\n' +
    'lambert = """\nmaterial\nC = max(0, L̂⋅N̂)`k_d` + 0.05`k_d`\nL̂ = (`P_L` - p)/‖`P_L` - p‖\nwhere\np ∈ ℝ³\nN̂ ∈ ℝ³\nI ∈ ℝ³\n' +
    '`P_L` ∈ ℝ³\n`k_d` ∈ [0,1]x[0,1]x[0,1] default = (0.8, 0.5, 0.2)\n"""\n' +
    '[camera]\nposition = [0, 7, -13]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [-5, 8, -6]\n' +
    '[[shapes]]\ntype = "ground"\nmaterial = "lambert"\n';
  let side = 1;
  while (side * side * 10 < n) side++;
  for (let i = 0; i < n; i++) {
    const x = (i % side) - side / 2 + 0.1 * Math.sin(i), z = Math.floor(i / side) % side - side / 2, y = Math.floor(i / (side * side)) * 0.5 - 0.7;
    // tilted about two axes: a whole matrix per ring (a tilt about x alone is two scalar tables, too little for the
    // texture), each by its own angle (tilts that repeat keep one period of their table)
    s += `[[shapes]]\ntype = "ring"\nmaterial = "lambert"\ntransform = "T((${x.toFixed(4)}, ${y}, ${z}))⋅\`R_y\`(0.3)⋅\`R_x\`(${(0.4 * (i % 7) + 0.1 * Math.sin(2.3 * i)).toFixed(3)})"\n`;
  }
  return s;
}
// The rings are in no bounding-volume hierarchy (no `bound`): the page evaluates all 400 at every step, which
// SwiftShader took 30-60 s a frame to draw on a 120×200 canvas (a 440×200 page less the 320-pixel panel) on two
// cores: the canvas is 120×100.
const ringsView = { width: 440, height: 100 };
for (const n of [100, 400]) fs.writeFileSync(path.join(tmp, `rings_${n}.iq`), ringsScene(n));
for (const [n, storage] of parts.has("instances") ? [[100, "iqc_block_"], [400, "texture:"]] : []) {
  const scene = path.join(tmp, `rings_${n}.iq`), out = path.join(tmp, `rings_${n}.html`);
  execFileSync(iqc, [scene, "--target", "html", "-o", out], { stdio: "pipe" });
  const { page, errors } = await open("file://" + out, ringsView);
  check(errors.length === 0, `${n} rings: no console errors ${errors.join(" | ")}`);
  await page.evaluate(() => document.getElementById("play").click());  // paused: a frame only when something changes
  const before = await picture(page);
  check(before.colours > 10 && before.mean > 1, `${n} rings: the canvas is not blank (${before.colours} colours)`);
  const frames = await page.evaluate(() => window.iqcFrames);
  const moved = await page.evaluate(prefix => {
    let k = 0;
    for (const s of document.querySelectorAll("#params input[type=color]"))
      if (s.dataset.colour.startsWith(prefix)) {
        s.value = "#202020";  // the rings' colour (k_d ∈ [0,1]³: a colour picker), so the frame costs what it did
        s.dispatchEvent(new Event("input"));
        k++;
      }
    return k;
  }, storage);
  check(moved === n, `${n} rings: a colour picker per ring stored in ${storage}… (${moved})`);
  await waitFor(page, f => window.iqcFrames > f, frames);
  const after = await picture(page);
  // Thin rings are few pixels: compare the whole canvas's mean, not the sampled digest.
  check(Math.abs(after.mean - before.mean) > 0.05, `${n} rings: their sliders change the picture (mean ${before.mean.toFixed(3)} → ${after.mean.toFixed(3)})`);
  await page.close();
}

// three.js: the webgl2 shader and --meta JSON on a RawShaderMaterial give the html page's picture — with
// plain uniforms (two_tori), uniform blocks (100 tilted rings) and the data texture (400).
// Serves three.html, three and the scene's --target threejs module at http://iqc.test/ (module scripts need http).
function threeFiles(input) {
  const dir = fs.mkdtempSync(path.join(tmp, "three-"));
  execFileSync(iqc, [input, "--target", "threejs", "-o", path.join(dir, "scene.mjs")], { stdio: "pipe" });
  return {
    "three.html": path.join(src, "tests/browser/three.html"),
    "three.module.js": path.join(src, "tests/browser/node_modules/three/build/three.module.js"),
    "scene.mjs": path.join(dir, "scene.mjs"),
  };
}
async function routeThree(page, files) {
  await page.route("http://iqc.test/**", route => {
    const file = files[new URL(route.request().url()).pathname.slice(1)];
    if (!file) return route.fulfill({ status: 404, body: "" });
    const type = file.endsWith(".js") || file.endsWith(".mjs") ? "text/javascript" : file.endsWith(".html") ? "text/html" : "text/plain";
    return route.fulfill({ status: 200, contentType: type, body: fs.readFileSync(file) });
  });
}
async function threeMatchesPage(label, input, viewport) {
  const dir = fs.mkdtempSync(path.join(tmp, "three-"));
  const files = threeFiles(input);
  const out = path.join(dir, "ref.html");
  execFileSync(iqc, [input, "--target", "html", "-o", out], { stdio: "pipe" });
  const ref = await open("file://" + out, viewport);
  await ref.page.evaluate(() => document.getElementById("play").click());
  const size = await ref.page.evaluate(() => [document.getElementById("canvas").width, document.getElementById("canvas").height]);
  const expected = await picture(ref.page);
  const page = await browser.newPage({ viewport });
  const errors = [];
  page.on("console", m => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", e => errors.push(String(e)));
  await routeThree(page, files);
  await page.goto(`http://iqc.test/three.html?w=${size[0]}&h=${size[1]}`);
  await waitFor(page, () => window.iqcFrames > 0);
  const got = await picture(page);
  const diff = got.data.reduce((s, v, i) => s + Math.abs(v - expected.data[i]), 0) / got.data.length;
  check(errors.length === 0, `three.js, ${label}: no console errors ${errors.join(" | ")}`);
  check(got.data.length === expected.data.length && diff < 2 && got.colours > 10,
        `three.js, ${label}: the same picture as the html page (mean difference ${diff.toFixed(2)} of 255, ${size[0]}×${size[1]})`);
  await page.close();
  await ref.page.close();
}
if (parts.has("threejs")) {
  await threeMatchesPage("two_tori (uniforms)", path.join(src, "examples", "two_tori.md"), { width: 480, height: 270 });
  await threeMatchesPage("100 rings (data texture: the threejs target has no uniform blocks)", path.join(tmp, "rings_100.iq"), ringsView);
  await threeMatchesPage("400 rings (data texture)", path.join(tmp, "rings_400.iq"), ringsView);
}

// three.js occlusion: a raymarched unit sphere and two red boxes (MeshBasicMaterial), one in front of the sphere,
// one cutting into it, seen through a camera of the page's own (not the scene's): each hides what is behind it.
if (parts.has("threejs")) {
  const input = path.join(tmp, "occlusion.iq");
  fs.writeFileSync(input, '[camera]\nposition = [0, 0, -4]\ntarget = [0, 0, 0]\n[render]\noutput = "linear"\nbackground = [0.1, 0.2, 0.9]\n' +
                          '[[lights]]\nposition = [-3, 4, -5]\n[[shapes]]\ntype = "sphere"\nmaterial = "lambert"\n');
  const page = await browser.newPage({ viewport: { width: 320, height: 240 } });
  const errors = [];
  page.on("console", m => { if (m.type() === "error") errors.push(m.text()); });
  page.on("pageerror", e => errors.push(String(e)));
  await routeThree(page, threeFiles(input));
  await page.goto("http://iqc.test/three.html?w=320&h=240&mesh");
  await waitFor(page, () => window.iqcFrames > 0);
  const at = async point => page.evaluate(p => {
    const [x, y] = window.project(p);
    const c = document.getElementById("canvas"), gl = c.getContext("webgl2");
    const px = new Uint8Array(4);
    gl.readPixels(x, c.height - 1 - y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    return Array.from(px);
  }, point);
  const red = c => c[0] > 200 && c[1] < 40 && c[2] < 40;
  const sky = c => c[0] < 60 && c[1] < 80 && c[2] > 180;
  const front = await at([-0.3, 0, -2.0]), sphere = await at([0.65, 0, -0.76]), out = await at([1.1, 0, -0.7]);
  const bare = await at([-0.5, 0.6, -0.63]), corner = await at([2.5, 2.2, 0]);
  check(errors.length === 0, `three.js occlusion: no console errors ${errors.join(" | ")}`);
  check(red(front), `three.js occlusion: the box in front of the sphere hides it (${front})`);
  check(!red(sphere) && !sky(sphere), `three.js occlusion: the sphere hides the box behind its surface (${sphere})`);
  check(red(out), `three.js occlusion: the box where it leaves the sphere shows (${out})`);
  check(!red(bare) && !sky(bare), `three.js occlusion: the sphere alone (${bare})`);
  check(sky(corner), `three.js occlusion: the background where nothing is (${corner})`);
  await page.close();
}

// A narrow window (a phone held upright, 390×700): the picture takes the whole width, the panel is under it.
if (parts.has("pages")) {
  const out = path.join(tmp, "narrow.html");
  execFileSync(iqc, [path.join(src, "examples", "two_tori.md"), "--target", "html", "-o", out], { stdio: "pipe" });
  const { page, errors } = await open("file://" + out, { width: 390, height: 700 });
  const box = await page.evaluate(() => {
    const v = document.getElementById("canvas").getBoundingClientRect(), p = document.getElementById("panel").getBoundingClientRect();
    return { w: v.width, h: v.height, bottom: v.bottom, panelTop: p.top, panelW: p.width };
  });
  check(box.w === 390 && box.h >= 300 && box.panelTop >= box.bottom && box.panelW === 390,
        `narrow window: the canvas takes the width (${box.w}×${box.h}), the panel is under it (top ${box.panelTop}, ${box.panelW} wide)`);
  const pic = await picture(page);
  check(errors.length === 0 && pic.colours > 10, `narrow window: drawn, no console errors (${pic.colours} colours) ${errors.join(" | ")}`);
  await page.close();
}

// Pages of scene `movedText` (with `move`, run in the page, setting sliders and returning their values) and of
// `atText` (those values as defaults): the picture before and after the move, the defaults' picture, and how many
// samples differ from it by more than 8/255. Checks that neither page logs an error.
async function movedAgainstDefaults(name, movedText, atText, move) {
  const moved = path.join(tmp, name + "_moved.html"), at = path.join(tmp, name + "_at.html");
  fs.writeFileSync(path.join(tmp, name + "_moved.iq"), movedText);
  fs.writeFileSync(path.join(tmp, name + "_at.iq"), atText);
  execFileSync(iqc, [path.join(tmp, name + "_moved.iq"), "--target", "html", "-o", moved], { stdio: "pipe" });
  execFileSync(iqc, [path.join(tmp, name + "_at.iq"), "--target", "html", "-o", at], { stdio: "pipe" });
  const a = await open("file://" + moved);
  const before = await picture(a.page);
  const frames = await a.page.evaluate(() => window.iqcFrames);
  const values = await a.page.evaluate(move);
  await waitFor(a.page, n => window.iqcFrames > n, frames);  // (every input in one frame)
  const seen = await picture(a.page);
  const b = await open("file://" + at);
  const expected = await picture(b.page);
  const off = seen.data.filter((v, i) => Math.abs(v - expected.data[i]) > 8).length;
  check(a.errors.length === 0 && b.errors.length === 0, `${name}: no console errors ${a.errors.concat(b.errors).join(" | ")}`);
  await a.page.close();
  await b.page.close();
  return { values, before, seen, off };
}

// K and the scene box follow the sliders (stop 55): where a slider moves in the page, the shader divides by the K of
// its cell and clips to the box over the sliders' ranges (the defaults' box only while they are near their defaults).
// Moved to a = 0.15, f = 20.5, the page draws what a page compiled with those defaults draws: no hole where a cell's K
// were too small, nothing clipped by a box too small.
if (parts.has("pages")) {
  const scene = (a, f) => '[modules]\nbumpy = """\nshape\nsin from trigonometry\nD = ‖p‖ - 1 + a sin(f p_1) sin(f p_2) sin(f p_3)\n' +
    `where\np ∈ ℝ³\na ∈ [0, 0.3] default = ${a}\nf ∈ [1, 40] default = ${f}\n"""\n[camera]\nposition = [0, 1.2, -3.2]\n[[shapes]]\ntype = "bumpy"\n`;
  const { values, seen, off } = await movedAgainstDefaults("cells", scene(0.05, 8), scene(0.15, 20.5), () => {
    const s = document.querySelectorAll("#params input[type=range]");
    s[0].value = 0.15; s[0].dispatchEvent(new Event("input"));
    s[1].value = 20.5; s[1].dispatchEvent(new Event("input"));
    return Array.from(s).map(x => Number(x.value));
  });
  check(Math.abs(values[0] - 0.15) < 1e-3 && Math.abs(values[1] - 20.5) < 0.02 && off <= 0.01 * seen.data.length && seen.colours > 50,
        `cells: sliders moved to (${values.join(", ")}) draw what their defaults draw (${off} of ${seen.data.length} samples differ)`);
}

// A group of 48 bumpy balls (stop 59): K, the scene box and the bounding spheres are taken over the hull of the
// members' values, guarded in iqc_prepare by a loop over the members. One member's sliders moved far past the others'
// (r 0.3 → 1.2, a → 0) in the page draw what a page compiled with those values draws: the whole's K, every node of the
// hierarchy entered, no sphere of the hull standing in for that member, no box clipping it.
if (parts.has("pages")) {
  const scene = (r5, a5) => {
    let s = '[modules]\nbump = """\nshape\nD = ‖p‖ - r + a sin(f p_1) sin(f p_2) sin(f p_3)\nsin from trigonometry\nwhere\n' +
      'p ∈ ℝ³\nr ∈ [0.1, 2] default = 0.4\na ∈ [0, 0.5] default = 0.03\nf ∈ [0, 60] default = 10\n"""\n' +
      '[camera]\nposition = [0, 4, -8]\ntarget = [0, 0, 1]\n[[lights]]\nposition = [-4, 8, -5]\n';
    for (let k = 0; k < 48; ++k) {
      const r = k === 5 ? r5 : 0.3 + 0.03 * (k % 7), a = k === 5 ? a5 : 0.02 * (k % 5);
      s += `[[shapes]]\ntype = "bump"\nname = "b${k}"\ntransform = "T((${-3.5 + (k % 8)}, 0, ${-1 + Math.floor(k / 8) * 1.5}))"\n` +
        `shape_params = { r = ${r}, a = ${a}, f = ${4 + 3 * (k % 7) + Math.floor(k / 7)} }\n`;
    }
    return s;
  };
  const { values: found, before, seen, off } = await movedAgainstDefaults("hull", scene(0.45, 0), scene(1.2, 0), () => {
    for (const d of document.querySelectorAll("#params details"))
      if (d.querySelector("summary").textContent === "b5")
        for (const s of d.querySelectorAll("input[type=range]"))
          if (s.dataset.name === "r") { s.value = 1.2; s.dispatchEvent(new Event("input")); return Number(s.value); }
    return -1;
  });
  check(Math.abs(found - 1.2) < 0.01 && differs(before, seen) && off <= 0.01 * seen.data.length && seen.colours > 50,
        `hull: a member's r moved to ${found} past its group's values draws what its default there draws (${off} of ${seen.data.length} samples differ)`);
}

// A phone (390×844 at 3 device pixels per CSS pixel, touch): the drawing buffer is the canvas's exact size (60vh is
// 506.4 CSS pixels: clientHeight's whole pixels made it a row short), and a finger's drag on the picture reaches
// the page as pointer moves (the browser's pan cancelled it after two and scrolled the page).
if (parts.has("pages")) {
  const scene = path.join(tmp, "orbit.iq"), out = path.join(tmp, "orbit.html");
  fs.writeFileSync(scene, '[camera]\nposition = [0, 1, -4]\norbit = true\n[[shapes]]\ntype = "sphere"\n');
  execFileSync(iqc, [scene, "--target", "html", "-o", out], { stdio: "pipe" });
  const ctx = await browser.newContext({ viewport: { width: 390, height: 844 }, deviceScaleFactor: 3, isMobile: true, hasTouch: true });
  const page = await ctx.newPage();
  const errors = [];
  page.on("console", m => { if (m.type() === "error") errors.push(m.text()); });
  await page.goto("file://" + out);
  await waitFor(page, () => window.iqcFrames > 0);
  const size = await page.evaluate(() => {
    const c = document.getElementById("canvas"), r = c.getBoundingClientRect();
    return { w: c.width, h: c.height, cw: r.width * devicePixelRatio, ch: r.height * devicePixelRatio };
  });
  check(size.w === Math.round(size.cw) && size.h === Math.round(size.ch),
        `phone: the drawing buffer ${size.w}×${size.h} is the canvas's ${size.cw.toFixed(1)}×${size.ch.toFixed(1)} device pixels`);
  await page.evaluate(() => {
    window.touchLog = [];
    for (const t of ["pointermove", "pointercancel"]) document.getElementById("canvas").addEventListener(t, () => window.touchLog.push(t));
  });
  const at = await page.evaluate(() => { const r = document.getElementById("canvas").getBoundingClientRect(); return [r.x + r.width / 2, r.y + r.height / 2]; });
  const cdp = await ctx.newCDPSession(page);
  const touch = (type, x, y) => cdp.send("Input.dispatchTouchEvent", { type, touchPoints: type === "touchEnd" ? [] : [{ x, y, id: 1 }] });
  await touch("touchStart", at[0], at[1]);
  for (let i = 1; i <= 10; i++) { await touch("touchMove", at[0] + 6 * i, at[1] - 12 * i); await new Promise(r => setTimeout(r, 20)); }
  await touch("touchEnd");
  const log = await page.evaluate(() => window.touchLog), scrolled = await page.evaluate(() => window.scrollY);
  const moves = log.filter(e => e === "pointermove").length;
  check(moves >= 8 && !log.includes("pointercancel") && scrolled === 0,
        `phone: a finger's drag on the picture is ${moves} pointer moves, ${log.includes("pointercancel") ? "then cancelled" : "not cancelled"}, the page scrolled ${scrolled}`);
  check(errors.length === 0, `phone: no console errors ${errors.join(" | ")}`);
  await ctx.close();
}

// Long words and tiny windows: the page is never wider than the window (a title of one long word made it 1,740
// pixels wide at 360; a fieldset of sliders, 277 at 250).
if (parts.has("pages")) {
  const scene = path.join(tmp, "long_title.iq"), out = path.join(tmp, "long_title.html");
  fs.writeFileSync(scene, `title = "${"Supercalifragilisticexpialidocious_".repeat(6)}"\n[[shapes]]\ntype = "torus"\n`);
  execFileSync(iqc, [scene, "--target", "html", "-o", out], { stdio: "pipe" });
  const lights = path.join(tmp, "lights.html");
  execFileSync(iqc, [path.join(src, "examples", "lights_and_effects.iq"), "--target", "html", "-o", lights], { stdio: "pipe" });
  for (const [file, viewport] of [[out, { width: 360, height: 640 }], [out, { width: 1000, height: 400 }], [lights, { width: 250, height: 500 }]]) {
    const { page, errors } = await open("file://" + file, viewport);
    await page.evaluate(() => document.querySelectorAll("details").forEach(d => { d.open = true; }));
    const widths = await page.evaluate(() => ({ page: document.documentElement.scrollWidth, panel: document.getElementById("panel").scrollWidth,
                                                 panelBox: document.getElementById("panel").clientWidth }));
    check(widths.page <= viewport.width && widths.panel <= widths.panelBox && errors.length === 0,
          `${path.basename(file)} at ${viewport.width}×${viewport.height}: the page ${widths.page} and the panel's content ${widths.panel} fit (${widths.panelBox}) ${errors.join(" | ")}`);
    await page.close();
  }
}

if (parts.has("pages")) {
  const hostile = "</script><script>alert(1)</script>";
  const scene = path.join(tmp, "hostile.iq");
  fs.writeFileSync(scene, `title = "${hostile}"\n[[shapes]]\ntype = "torus"\n`);
  const out = path.join(tmp, "hostile.html");
  execFileSync(iqc, [scene, "--target", "html", "-o", out], { stdio: "pipe" });
  const { page, errors } = await open("file://" + out);
  check(errors.length === 0, `hostile title: no dialog, no error ${errors.join(" | ")}`);
  check((await page.textContent("#title")) === hostile, "hostile title: shown as text");
  await page.close();
}

if (parts.has("pages")) {
  const dir = path.join(tmp, "serve");
  fs.mkdirSync(dir);
  const ring = r => `shape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ [0,3] default = ${r}: radius\n`;
  fs.writeFileSync(path.join(dir, "ball.iql"), ring("1"));
  fs.writeFileSync(path.join(dir, "scene.iq"), `title = "served"\ninclude = ["ball.iql"]\n[camera]\nposition = [0, 0, -4]\n[[shapes]]\ntype = "ball"\n`);
  const server = spawn(iqc, ["serve", path.join(dir, "scene.iq"), "--port", "0", "--poll", "0.05"]);
  const url = await new Promise((resolve, reject) => {
    let text = "";
    server.stdout.on("data", d => { text += d; const m = text.match(/http:\/\/127\.0\.0\.1:\d+\//); if (m) resolve(m[0]); });
    server.on("exit", () => reject(new Error("iqc serve exited")));
  });
  try {
    const { page, errors } = await open(url);
    const first = await picture(page);
    // Move a slider, then edit the module: the page reloads with the new default for r but keeps the slider.
    await page.evaluate(() => {
      const s = document.querySelector("#params input[type=range]");
      s.value = 0.5; s.dispatchEvent(new Event("input"));
    });
    const t0 = Date.now();
    const reloaded = page.waitForEvent("load");
    fs.writeFileSync(path.join(dir, "ball.iql"), ring("1.5") + "\n");
    await reloaded;
    await waitFor(page, () => window.iqcFrames > 0);
    const ms = Date.now() - t0;
    console.log(`measure: serve, module saved → reloaded page drawn in ${ms} ms`);
    const kept = await page.evaluate(() => Number(document.querySelector("#params input[type=range]").value));
    check(Math.abs(kept - 0.5) < 0.01, `serve: the slider kept its value (${kept})`);
    check(differs(first, await picture(page)), "serve: the picture changed");
    // A broken module: the page shows the error with its location.
    const broken = page.waitForEvent("load");
    fs.writeFileSync(path.join(dir, "ball.iql"), "shape\nD = ‖p‖ - radius\nwhere\np ∈ ℝ³\n");
    await broken;
    const text = await page.textContent("#error");
    check(/ball\.iql:2:\d+: error: undefined name/.test(text), `serve: the error is shown in the page (${text.split("\n")[0]})`);
    // Fixed again: the error page reloads by itself and draws (it never polled: stop 44's trial).
    const fixed = page.waitForEvent("load", { timeout: 30000 });
    fs.writeFileSync(path.join(dir, "ball.iql"), ring("1"));
    let recovered = true;
    try { await fixed; await waitFor(page, () => window.iqcFrames > 0, undefined, 30000); } catch { recovered = false; }
    const shown = recovered && await page.evaluate(() => getComputedStyle(document.getElementById("error")).display !== "none");
    check(recovered && !shown, `serve: fixed, the error page reloads and draws (${recovered ? "reloaded" : "no reload in 30 s"})`);
    check(errors.length === 0, `serve: no console errors ${errors.join(" | ")}`);
  } finally {
    server.kill();
  }
}

await browser.close();
if (checks === 0) { console.log("FAIL no check ran"); failures++; }
console.log(failures ? `${failures} failed` : `all ${checks} passed`);
process.exit(failures ? 1 : 0);
