#!/usr/bin/env node
// node web/cli.mjs decode IN > OUT: the raw float64 z-grid of an mzc file, as `mzc decode`
// writes it; node web/cli.mjs triangulate IN [--jump-angle A] > OUT.obj: its mesh as the OBJ
// `mzc triangulate IN --vertices all --format obj` writes. A bad file gets one line on stderr and exit
// status 1, and nothing on stdout.

import { readFileSync } from "node:fs";
import { decode, writeZgrid, formatNumber } from "./mzc.mjs";
import { triangulate } from "./triangulate.mjs";

const USAGE = "usage: node web/cli.mjs decode IN > OUT\n       node web/cli.mjs triangulate IN [--jump-angle A] > OUT.obj";

/** Each command's output bytes from the decoded grid and its options. */
const COMMANDS = {
  decode: (grid) => writeZgrid(grid),
  triangulate: (grid, options) => objText(triangulate(grid, options)),
};

/** The OBJ mzc writes: `v x y z` in Python's repr of each float (then `r g b`, each level / 255,
 * when the mesh has colours), then `f a b c` from 1. */
function objText({ positions, indices, colors }) {
  const repr = (x) => { const s = formatNumber(x); return /^-?\d+$/.test(s) ? `${s}.0` : s; };
  const lines = [];
  for (let i = 0; i < positions.length; i += 3) {
    const rgb = colors ? ` ${repr(colors[i] / 255)} ${repr(colors[i + 1] / 255)} ${repr(colors[i + 2] / 255)}` : "";
    lines.push(`v ${repr(positions[i])} ${repr(positions[i + 1])} ${repr(positions[i + 2])}${rgb}\n`);
  }
  for (let i = 0; i < indices.length; i += 3) lines.push(`f ${indices[i] + 1} ${indices[i + 1] + 1} ${indices[i + 2] + 1}\n`);
  return lines.join("");
}

/** The command, input name and options of the arguments, or null when they are not a usage. */
function parsed(args) {
  const [command, name, flag, value] = args;
  if (!COMMANDS[command] || name === undefined) return null;
  if (args.length === 2) return { command, name, options: {} };
  const angle = Number(value);
  if (command !== "triangulate" || args.length !== 4 || flag !== "--jump-angle" || value === "" || !(angle >= 0)) return null;
  return { command, name, options: { jumpAngle: angle } };
}

/** Runs the command line; returns the exit status. */
function main(args) {
  const run = parsed(args);
  if (!run) {
    process.stderr.write(`${USAGE}\n`);
    return 2;
  }
  let out;
  try {
    const grid = decode(readFileSync(run.name === "-" ? 0 : run.name));
    if (grid.cut) process.stderr.write(`mzc: warning: ${run.name}: ${grid.cut}\n`);   // a cut 9.0 file, decoded coarser
    out = COMMANDS[run.command](grid, run.options);
  } catch (error) {
    process.stderr.write(`mzc: ${run.name}: ${error.code === "ENOENT" ? "no such file" : error.message}\n`);
    return 1;
  }
  process.stdout.on("error", (error) => {
    if (error.code !== "EPIPE") process.stderr.write(`mzc: stdout: ${error.message}\n`);
    process.exit(1);
  });
  process.stdout.write(out);
  return 0;
}

process.exitCode = main(process.argv.slice(2));
