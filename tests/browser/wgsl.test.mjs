// The wgsl target (run by ctest). Usage: node wgsl.test.mjs IQC_BINARY SOURCE_DIR [INPUT...]
// (with INPUTs: those scenes instead of the examples and ring scenes; IQC_WGSL_DUMP=DIR keeps both pictures)
//  1. Tint (Dawn for Node, null backend: tests/browser/wgsl-validate.mjs) accepts the --target wgsl output of
//     every example, of ring scenes whose instances fill a uniform block (100) and the data texture (400), of
//     the hand-written Shadertoy references (bench/handwritten/) and of tests/wgsl/semantics.frag: the module
//     compiles and its vs_main/fs_main make a render pipeline.
//  2. Chromium's WebGPU (Dawn on SwiftShader's Vulkan) draws each of them from the WGSL and --meta alone (the
//     blocks' bytes, the data texture, the camera's defaults): the same picture as `iqc render --target webgl2`
//     (Mesa's llvmpipe), within a small tolerance (two rasterisers, two float implementations); the
//     self-checking shader is green (each of its checks runs one construct of the translation).
import { chromium } from "playwright-core";
import { execFileSync, spawnSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";

const [iqc, src, ...only] = process.argv.slice(2);
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), "iqc-wgsl-"));
// Removed at exit (IQC_KEEP_TEST_FILES=1 keeps it, to look at): every run left one behind.
process.on("exit", () => { if (!process.env.IQC_KEEP_TEST_FILES) fs.rmSync(tmp, { recursive: true, force: true }); });
let failures = 0;
const check = (ok, what) => { console.log((ok ? "ok   " : "FAIL ") + what); if (!ok) failures++; };

const inputs = only.length ? only.map(f => path.resolve(f)) : fs.readdirSync(path.join(src, "examples"))
  .filter(f => /\.(md|iq)$/.test(f)).sort().map(f => path.join(src, "examples", f));
if (!only.length) {
  // Shadertoy shaders nobody generated: the hand-written references, and a self-checking shader that is green
  // when every construct computes what it should (tests/wgsl/semantics.frag)
  for (const f of fs.readdirSync(path.join(src, "bench/handwritten")).filter(f => f.endsWith(".frag")).sort())
    inputs.push(path.join(src, "bench/handwritten", f));
  inputs.push(path.join(src, "tests/wgsl/semantics.frag"));
}
for (const n of only.length ? [] : [100, 400]) {
  const scene = path.join(tmp, `rings_${n}.iq`);
  fs.writeFileSync(scene, execFileSync("bash", [path.join(src, "bench/rings.sh"), String(n), "irregular"]));
  inputs.push(scene);
}

const W = 96, H = 64;
const cases = inputs.map(input => {
  const base = path.join(tmp, path.basename(input));
  execFileSync(iqc, [input, "--target", "wgsl", "-o", base + ".wgsl", "--meta", base + ".json", "-q"], { stdio: "pipe" });
  const frag = /\.(frag|glsl)$/.test(input);  // a Shadertoy shader: drawn as it is
  execFileSync(iqc, ["render", input, ...(frag ? [] : ["--target", "webgl2"]), "--size", `${W}x${H}`, "-o", base + ".png", "-q"], { stdio: "pipe" });
  return { name: path.basename(input), wgsl: base + ".wgsl", meta: base + ".json", png: base + ".png", frag };
});

// 1. Tint
const v = spawnSync("node", [path.join(src, "tests/browser/wgsl-validate.mjs"), ...cases.map(c => c.wgsl)], { encoding: "utf8" });
for (const c of cases)
  check(v.stdout.split("\n").includes(`ok ${c.wgsl}`), `${c.name}: Tint accepts the WGSL and its render pipeline`);
check(v.status === 0, `wgsl-validate exits 0 ${v.status ? v.stdout + v.stderr : ""}`);

// 2. WebGPU in Chromium. WebGPU needs a secure context: the page is served (by routing) at http://localhost/.
const browser = await chromium.launch({
  executablePath: process.env.IQC_CHROMIUM || "/usr/bin/chromium",
  args: ["--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox", "--enable-unsafe-webgpu"],
});
const page = await browser.newPage();
const errors = [];
page.on("pageerror", e => errors.push(String(e)));
let files = {};
await page.route("http://localhost/**", route => {
  const file = files[new URL(route.request().url()).pathname.slice(1)];
  if (file === undefined) return route.fulfill({ status: 200, contentType: "text/html", body: "<!doctype html><title>wgsl</title>" });
  return route.fulfill({ status: 200, contentType: file.endsWith(".png") ? "image/png" : "text/plain", body: fs.readFileSync(file) });
});
await page.goto("http://localhost/");

// Draws the WGSL with the inputs --meta describes (what an engine does) and returns RGBA8 rows, top first.
async function drawWgsl(code, meta, W, H) {
  const adapter = await navigator.gpu.requestAdapter();
  if (!adapter) return { error: "no WebGPU adapter" };
  const device = await adapter.requestDevice();
  const errors = [];
  device.addEventListener("uncapturederror", e => errors.push(e.error.message));
  const module = device.createShaderModule({ code });
  for (const m of (await module.getCompilationInfo()).messages)
    if (m.type === "error") errors.push(`${m.lineNum}:${m.linePos}: ${m.message}`);
  const pad16 = n => Math.ceil(n / 16) * 16;  // WGSL rounds a uniform struct's size up to 16 bytes
  const fromBase64 = s => Uint8Array.from(atob(s), ch => ch.charCodeAt(0));
  const layoutEntries = [], groupEntries = [];
  const uniform = (binding, bytes) => {
    const buffer = device.createBuffer({ size: pad16(bytes.byteLength), usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(buffer, 0, bytes);
    layoutEntries.push({ binding, visibility: GPUShaderStage.FRAGMENT, buffer: { type: "uniform" } });
    groupEntries.push({ binding, resource: { buffer } });
  };
  // IqcInputs: the camera's defaults, the resolution, time 0
  const ib = meta.inputs_block;
  const inputs = new ArrayBuffer(pad16(ib.bytes));
  const f32 = new Float32Array(inputs), i32 = new Int32Array(inputs);
  const values = { ...(meta.camera ? meta.camera.defaults : {}), iResolution: [W, H, 1], iTime: 0, iTimeDelta: 0,
                   iFrameRate: 0, iMouse: [0, 0, 0, 0], iFrame: 0, iDate: [0, 0, 0, 0] };
  for (const m of ib.members) {
    const v = [].concat(values[m.name] ?? []);
    if (m.type === "mat3" || m.type === "mat4") {
      const n = m.type === "mat3" ? 3 : 4;
      for (let c = 0; c < n; c++) for (let r = 0; r < n; r++) f32[(m.offset + c * m.column_stride) / 4 + r] = v[c * n + r];
    } else if (m.type === "int") {
      i32[m.offset / 4] = v[0] ?? 0;
    } else {
      v.forEach((x, k) => { f32[m.offset / 4 + k] = x; });
    }
  }
  uniform(ib.binding, new Uint8Array(inputs));
  for (const b of meta.blocks) uniform(b.binding, fromBase64(b.data));
  if (meta.texture) {
    const t = meta.texture;
    const texture = device.createTexture({ size: [t.width, t.height], format: "rgba32float",
                                           usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST });
    device.queue.writeTexture({ texture }, fromBase64(t.data), { bytesPerRow: t.width * 16 }, [t.width, t.height]);
    layoutEntries.push({ binding: t.binding, visibility: GPUShaderStage.FRAGMENT, texture: { sampleType: "unfilterable-float" } });
    groupEntries.push({ binding: t.binding, resource: texture.createView() });
  }
  const bgl = device.createBindGroupLayout({ entries: layoutEntries });
  const pipeline = device.createRenderPipeline({
    layout: device.createPipelineLayout({ bindGroupLayouts: [bgl] }),
    vertex: { module, entryPoint: "vs_main" },
    fragment: { module, entryPoint: "fs_main", targets: [{ format: "rgba8unorm" }] },
    depthStencil: { format: "depth32float", depthWriteEnabled: true, depthCompare: "always" },
  });
  const group = device.createBindGroup({ layout: bgl, entries: groupEntries });
  const colour = device.createTexture({ size: [W, H], format: "rgba8unorm", usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC });
  const depth = device.createTexture({ size: [W, H], format: "depth32float", usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC });
  const bpr = Math.ceil(W * 4 / 256) * 256, dbpr = Math.ceil(W * 4 / 256) * 256;
  const out = device.createBuffer({ size: bpr * H, usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.MAP_READ });
  const dout = device.createBuffer({ size: dbpr * H, usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.MAP_READ });
  const enc = device.createCommandEncoder();
  const pass = enc.beginRenderPass({
    colorAttachments: [{ view: colour.createView(), loadOp: "clear", storeOp: "store", clearValue: [1, 0, 1, 1] }],
    depthStencilAttachment: { view: depth.createView(), depthLoadOp: "clear", depthStoreOp: "store", depthClearValue: 0.5 },
  });
  pass.setPipeline(pipeline);
  pass.setBindGroup(0, group);
  pass.draw(3);
  pass.end();
  enc.copyTextureToBuffer({ texture: colour }, { buffer: out, bytesPerRow: bpr }, [W, H]);
  enc.copyTextureToBuffer({ texture: depth, aspect: "depth-only" }, { buffer: dout, bytesPerRow: dbpr }, [W, H]);
  device.queue.submit([enc.finish()]);
  await out.mapAsync(GPUMapMode.READ);
  await dout.mapAsync(GPUMapMode.READ);
  const raw = new Uint8Array(out.getMappedRange());
  const draw = new Float32Array(dout.getMappedRange());
  const px = [], depths = [];
  for (let y = 0; y < H; y++) for (let x = 0; x < W * 4; x++) px.push(raw[y * bpr + x]);
  for (let y = 0; y < H; y++) for (let x = 0; x < W; x++) depths.push(draw[y * dbpr / 4 + x]);
  device.destroy();
  return { errors, px, depths };
}

async function decodePng(url) {
  const bitmap = await createImageBitmap(await (await fetch(url)).blob(), { colorSpaceConversion: "none", premultiplyAlpha: "none" });
  const c = new OffscreenCanvas(bitmap.width, bitmap.height);
  const ctx = c.getContext("2d");
  ctx.drawImage(bitmap, 0, 0);
  return Array.from(ctx.getImageData(0, 0, bitmap.width, bitmap.height).data);
}

for (const c of cases) {
  files = { "scene.wgsl": c.wgsl, "ref.png": c.png };
  const code = fs.readFileSync(c.wgsl, "utf8");
  const meta = JSON.parse(fs.readFileSync(c.meta, "utf8"));
  const got = await page.evaluate(`(${drawWgsl.toString()})(${JSON.stringify(code)}, ${JSON.stringify(meta)}, ${W}, ${H})`);
  const ref = await page.evaluate(`(${decodePng.toString()})("http://localhost/ref.png")`);
  check(!got.error && got.errors.length === 0, `${c.name}: WebGPU draws the WGSL without errors ${got.error ?? ""} ${(got.errors ?? []).join(" | ")}`);
  if (got.error) continue;
  let sum = 0, off = 0, colours = new Set(), refColours = new Set();
  for (let i = 0; i < W * H; i++) {
    let worst = 0;
    for (let k = 0; k < 3; k++) {
      const d = Math.abs(got.px[4 * i + k] - ref[4 * i + k]);
      sum += d;
      worst = Math.max(worst, d);
    }
    if (worst > 24) off++;
    colours.add((got.px[4 * i] << 16) | (got.px[4 * i + 1] << 8) | got.px[4 * i + 2]);
    refColours.add((ref[4 * i] << 16) | (ref[4 * i + 1] << 8) | ref[4 * i + 2]);
  }
  const mean = sum / (W * H * 3);
  if (process.env.IQC_WGSL_DUMP) {  // the WebGPU picture as a PPM next to iqc render's PNG, for a look
    fs.mkdirSync(process.env.IQC_WGSL_DUMP, { recursive: true });
    const rgb = Buffer.alloc(W * H * 3);
    for (let i = 0; i < W * H; i++) for (let k = 0; k < 3; k++) rgb[3 * i + k] = got.px[4 * i + k];
    fs.writeFileSync(path.join(process.env.IQC_WGSL_DUMP, c.name + ".webgpu.ppm"), Buffer.concat([Buffer.from(`P6 ${W} ${H} 255\n`), rgb]));
    fs.copyFileSync(c.png, path.join(process.env.IQC_WGSL_DUMP, c.name + ".render.png"));
  }
  // Bit-identical on most examples; christmas_tree's terrain hashes fract(43758.5453·sin(x)) with x in the
  // hundreds, where SwiftShader's and llvmpipe's sin differ in the last bits (mean 2.7, 1.5% of pixels).
  check(ref.length === got.px.length && mean < 3 && off <= W * H * 0.02 &&
        colours.size >= Math.min(10, refColours.size),
        `${c.name}: the same picture as iqc render (mean difference ${mean.toFixed(2)} of 255, ${off} of ${W * H} pixels off by more than 24, ${colours.size} colours)`);
  if (c.name === "semantics.frag") {
    const green = got.px.every((v, i) => v === [0, 255, 0, 255][i % 4]);
    check(green, `semantics.frag: every construct computes its answer under WebGPU (first pixel ${got.px.slice(0, 4)}; blue = the failing check)`);
  }
  if (c.frag) continue;
  // depth: written (not the cleared 0.5) somewhere, and in [0, 1]
  const written = got.depths.filter(d => d !== 0.5).length;
  check(written > 0 && got.depths.every(d => d >= 0 && d <= 1), `${c.name}: fs_main writes depth in [0, 1] (${written} pixels)`);
}
check(errors.length === 0, `no page errors ${errors.join(" | ")}`);
await browser.close();
fs.rmSync(tmp, { recursive: true, force: true });
console.log(failures ? `${failures} FAILED` : "all passed");
process.exit(failures ? 1 : 0);
