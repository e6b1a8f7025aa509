#!/usr/bin/env node
// node web/cli.mjs decode IN > OUT: the raw float64 z-grid of an mzc file, as `mzc decode`
// writes it. A bad file gets one line on stderr and exit status 1, and nothing on stdout.

import { readFileSync } from "node:fs";
import { decode, writeZgrid } from "./mzc.mjs";

const USAGE = "usage: node web/cli.mjs decode IN > OUT";

/** Runs the command line; returns the exit status. */
function main(args) {
  if (args.length !== 2 || args[0] !== "decode") {
    process.stderr.write(`${USAGE}\n`);
    return 2;
  }
  const name = args[1];
  let out;
  try {
    out = writeZgrid(decode(readFileSync(name === "-" ? 0 : name)));
  } catch (error) {
    process.stderr.write(`mzc: ${name}: ${error.code === "ENOENT" ? "no such file" : error.message}\n`);
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
