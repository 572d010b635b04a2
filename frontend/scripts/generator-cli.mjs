// The command line the type generators share (gen-protocol.mjs, gen-api/gen-api.mjs):
// read a JSON document from a file, stdin or a Python module's output, and write the
// generated TypeScript to a file or stdout.
//
//   node GENERATOR < doc.json                  # TypeScript to stdout
//   node GENERATOR doc.json                    # same, from a file
//   node GENERATOR --from-python [--out FILE]  # runs the Python module itself
//   ... --out FILE                             # write FILE instead of stdout

import { execFileSync } from "node:child_process";
import { existsSync, mkdirSync, readFileSync, writeFileSync } from "node:fs";
import { dirname, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const repoRoot = resolve(dirname(fileURLToPath(import.meta.url)), "..", "..");

/** `{ fromPython, out, input }` from the arguments; `--help` prints `usage` and exits. */
export function parseArgs(argv, usage) {
  const args = { fromPython: false, out: null, input: null };
  for (let i = 0; i < argv.length; i++) {
    const arg = argv[i];
    if (arg === "--from-python") args.fromPython = true;
    else if (arg === "--out") args.out = argv[++i];
    else if (arg === "-h" || arg === "--help") {
      process.stdout.write(usage);
      process.exit(0);
    } else if (arg.startsWith("-")) throw new Error(`unknown option ${arg}`);
    else args.input = arg;
  }
  if (args.out === undefined) throw new Error("--out needs a file path");
  return args;
}

/** All of stdin; read as a stream, since a synchronous read of a pipe can fail with EAGAIN. */
async function readStdin() {
  const chunks = [];
  for await (const chunk of process.stdin) chunks.push(chunk);
  return Buffer.concat(chunks).toString("utf8");
}

/** The input document's text: `python -m pythonModule`'s output, the file, or stdin. */
export async function readInput(args, pythonModule) {
  if (args.fromPython) {
    const venvPython = resolve(repoRoot, ".venv", "bin", "python");
    const python = existsSync(venvPython) ? venvPython : "python3";
    return execFileSync(python, ["-m", pythonModule], {
      cwd: repoRoot,
      encoding: "utf8",
      maxBuffer: 64 * 1024 * 1024,
      stdio: ["ignore", "pipe", "inherit"],
    });
  }
  return args.input ? readFileSync(args.input, "utf8") : readStdin();
}

/** Writes `text` to `--out` (creating its folder) or to stdout. */
export function writeOutput(args, text) {
  if (args.out) {
    mkdirSync(dirname(resolve(args.out)), { recursive: true });
    writeFileSync(args.out, text);
  } else {
    process.stdout.write(text);
  }
}
