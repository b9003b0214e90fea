#!/usr/bin/env node
// ONNX Runtime (the npm package onnxruntime-node, CPU) on the StarGAN generator that
// scripts/reference_stargan.py --onnx exports: the inference side by side of bench/compare.sh and the runner of
// the agreement test (tests/golden/onnx_test.py). One intra-op and one inter-op thread, sequential execution,
// every graph optimisation on.
//
// Usage:
//   node bench/onnxruntime_bench.js check
//       Prints `onnxruntime-node <version> (<directory>)` and exits 0, or says what is missing and exits 77.
//   node bench/onnxruntime_bench.js time MODEL.onnx LABEL BATCHES [MIN_SECONDS]
//       For each batch size of the comma-separated BATCHES, times InferenceSession.run() on random x in [-1, 1] and
//       one-hot labels (every target in turn): two warm-up calls, then calls until MIN_SECONDS (default 1) have
//       passed (at least 3). Prints one line per batch:
//       `onnxruntime <LABEL> b<batch>: <us> us per call, <clips> clips/s (<calls> calls)`.
//   node bench/onnxruntime_bench.js run MODEL.onnx IN.json OUT.json
//       IN.json {"batch": B, "x": [B*3*H*W floats], "c": [B*C floats]}; writes {"y": [B*3*H*W floats]}.
// onnxruntime-node is looked for in $HANDEMO_ORT_DIR/node_modules (default: <repository>/build-ort, which
// `npm install --prefix build-ort onnxruntime-node --ignore-scripts` fills), then where Node looks by itself.
"use strict";
const fs = require("fs");
const path = require("path");

const SKIP = 77;

function loadOrt() {
  const dir = process.env.HANDEMO_ORT_DIR || path.join(__dirname, "..", "build-ort");
  const tried = [];
  for (const base of [path.join(dir, "node_modules", "onnxruntime-node"), "onnxruntime-node"]) {
    try {
      const ort = require(base);
      const pkg = require(path.join(path.dirname(require.resolve(base)), "..", "package.json"));
      return { ort, version: pkg.version, where: path.dirname(require.resolve(base)) };
    } catch (e) {
      tried.push(`${base}: ${e.code || e.message.split("\n")[0]}`);
    }
  }
  return { error: `onnxruntime-node not found (${tried.join("; ")}); npm install --prefix ${dir} onnxruntime-node --ignore-scripts installs it` };
}

async function openModel(ort, model) {
  return ort.InferenceSession.create(model, {
    executionProviders: ["cpu"],
    intraOpNumThreads: 1,
    interOpNumThreads: 1,
    executionMode: "sequential",
    graphOptimizationLevel: "all",
  });
}

// The model's H, W and C from its input shapes (x [batch, 3, H, W], c [batch, C]).
function inputShapes(s) {
  const meta = s.inputMetadata;
  if (!meta) return null;
  const byName = {};
  for (const m of Array.isArray(meta) ? meta : Object.values(meta)) byName[m.name] = m.shape;
  return byName.x && byName.c ? { H: byName.x[2], W: byName.x[3], C: byName.c[1] } : null;
}

function feeds(ort, x, c, batch, dims) {
  return {
    x: new ort.Tensor("float32", x, [batch, 3, dims.H, dims.W]),
    c: new ort.Tensor("float32", c, [batch, dims.C]),
  };
}

async function time(ort, model, label, batches, minSeconds) {
  const s = await openModel(ort, model);
  const dims = inputShapes(s);
  if (!dims || !(dims.H > 0 && dims.W > 0 && dims.C > 0)) throw new Error(`${model}: inputs are not x [batch, 3, H, W] and c [batch, C]`);
  let seed = 1;
  const random = () => ((seed = (seed * 1103515245 + 12345) % 2147483648) / 2147483648) * 2 - 1;
  for (const batch of batches) {
    const x = new Float32Array(batch * 3 * dims.H * dims.W).map(random);
    const c = new Float32Array(batch * dims.C);
    for (let n = 0; n < batch; ++n) c[n * dims.C + (n % dims.C)] = 1;
    const f = feeds(ort, x, c, batch, dims);
    await s.run(f);
    await s.run(f);
    let calls = 0;
    const start = process.hrtime.bigint();
    let elapsed = 0;
    while (calls < 3 || elapsed < minSeconds) {
      await s.run(f);
      ++calls;
      elapsed = Number(process.hrtime.bigint() - start) / 1e9;
    }
    const per = elapsed / calls;
    console.log(`onnxruntime ${label} b${batch}: ${(per * 1e6).toFixed(0)} us per call, ${(batch / per).toFixed(0)} clips/s (${calls} calls)`);
  }
}

async function run(ort, model, inPath, outPath) {
  const input = JSON.parse(fs.readFileSync(inPath, "utf8"));
  const s = await openModel(ort, model);
  const dims = inputShapes(s);
  const out = await s.run(feeds(ort, Float32Array.from(input.x), Float32Array.from(input.c), input.batch, dims));
  const tmp = `${outPath}.tmp${process.pid}`;
  fs.writeFileSync(tmp, JSON.stringify({ y: Array.from(out.y.data) }));
  fs.renameSync(tmp, outPath);  // a reader never sees half a file
}

async function main(argv) {
  const usage = () => {
    const text = fs.readFileSync(__filename, "utf8").split("\n");
    console.error(text.filter((l) => l.startsWith("//")).slice(4, 17).map((l) => l.slice(3)).join("\n"));
    return 2;
  };
  const mode = argv[0];
  if (!["check", "time", "run"].includes(mode)) return usage();
  const o = loadOrt();
  if (o.error) {
    console.log(`SKIP: ${o.error}`);
    return SKIP;
  }
  if (mode === "check") {
    console.log(`onnxruntime-node ${o.version} (${o.where})`);
    return 0;
  }
  if (mode === "time" && (argv.length === 4 || argv.length === 5)) {
    const batches = argv[3].split(",").map(Number);
    const minSeconds = argv.length === 5 ? Number(argv[4]) : 1;
    if (!batches.every((b) => Number.isInteger(b) && b > 0) || !(minSeconds >= 0)) return usage();
    await time(o.ort, argv[1], argv[2], batches, minSeconds);
    return 0;
  }
  if (mode === "run" && argv.length === 4) {
    await run(o.ort, argv[1], argv[2], argv[3]);
    return 0;
  }
  return usage();
}

main(process.argv.slice(2)).then(
  (rc) => process.exit(rc),
  (e) => {
    console.error(`onnxruntime_bench.js: ${e.message}`);
    process.exit(1);
  }
);
