// Which build of the core this browser can run. The core is built twice (.ci/lib.sh): for
// relaxed SIMD (fused multiply-add in the solver's kernels, faster) and for baseline SIMD.
// A plain script (no import or export), so that the module worker imports it and the classic
// service worker loads it with importScripts: both must make the same choice.
//
// This 36-byte module, one function using the relaxed-SIMD instruction i8x16.relaxed_swizzle,
// validates only where the browser has relaxed SIMD.
self.wslapCore = {
  relaxed: 'pkg/wslap_relaxed_bg.wasm',
  baseline: 'pkg/wslap_bg.wasm',
  hasRelaxedSimd() {
    return WebAssembly.validate(new Uint8Array([
      0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 15, 1, 13, 0, 65, 1,
      253, 15, 65, 2, 253, 15, 253, 128, 2, 11,
    ]));
  },
};
