// Validates WGSL files with Tint, WebGPU's shader compiler, inside Dawn for Node (the `webgpu` npm package),
// on Dawn's null backend: no GPU or Vulkan driver is needed. Each file is compiled (createShaderModule, the
// errors of getCompilationInfo) and built into a render pipeline with entry points vs_main and fs_main and
// `layout: "auto"` (Dawn checks the entry points' interface and the resources' bindings there).
//
//   node tests/browser/wgsl-validate.mjs FILE.wgsl...
//
// Prints "ok FILE" or the messages per file; exit status 1 when any file fails.
import { create, globals } from "webgpu";
import fs from "node:fs";

Object.assign(globalThis, globals);
const gpu = create(["backend=null"]);
const adapter = await gpu.requestAdapter();
if (!adapter) {
  console.error("wgsl-validate: Dawn's null backend gave no adapter");
  process.exit(2);
}
const device = await adapter.requestDevice();
let failed = 0;
for (const file of process.argv.slice(2)) {
  const code = fs.readFileSync(file, "utf8");
  const problems = [];
  device.pushErrorScope("validation");
  const module = device.createShaderModule({ code });
  const info = await module.getCompilationInfo();
  for (const m of info.messages)
    if (m.type === "error") problems.push(`${file}:${m.lineNum}:${m.linePos}: error: ${m.message}`);
  if (problems.length === 0) {
    device.createRenderPipeline({
      layout: "auto",
      vertex: { module, entryPoint: "vs_main" },
      fragment: { module, entryPoint: "fs_main", targets: [{ format: "rgba8unorm" }] },
      depthStencil: { format: "depth32float", depthWriteEnabled: true, depthCompare: "always" },
    });
  }
  const err = await device.popErrorScope();
  if (err && problems.length === 0) problems.push(`${file}: error: ${err.message}`);
  if (problems.length) {
    failed++;
    console.log(problems.join("\n"));
  } else {
    console.log(`ok ${file}`);
  }
}
device.destroy();
process.exit(failed ? 1 : 0);
