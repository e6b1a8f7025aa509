// dwt2d 2.0's transform: PyWavelets' periodization (spec/dwt2d.md, Transform of 2.0).
import { fail } from "./header.mjs";

export function relevantPeriodized2d() {
  fail("data", "mzc-dwt2d 2.0 is not read yet");
}
export function inversePeriodized2d() {}
