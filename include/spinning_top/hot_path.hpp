// SPINNING_TOP_FLATTEN marks per-step functions (explicit methods, driver bookkeeping): every call
// in their body (Eigen's fixed-size kernels, the model's derivative) is inlined, whatever the
// compiler's inlining budget for the translation unit.
// Why: GCC's inlining budget is per translation unit. When src/simulator.cpp instantiated every
// scene x method in one unit, the templates instantiated after the unit-growth limit
// (--param inline-unit-growth) was spent kept Eigen's 6-element `sum += a * k` and
// `y0 + dt * sum` as out-of-line calls through the PLT of the shared library: measured on the
// fixed tip (doc/integrators.md, "Per-step cost"), dop853 spent about 45 % of its time in such
// calls and cost 0.69 us per step, 0.30 us with them inlined. The factories are now one unit per
// scene (src/scenes/), and the attribute still pays there: without it rk4 executes 638 instead of
// 570 instructions per step and dop853 3199 instead of 3093 (callgrind, fixed tip). The results
// do not change (same operations in the same order: bit for bit).
#pragma once

#if defined(__GNUC__) || defined(__clang__)
#define SPINNING_TOP_FLATTEN __attribute__((flatten))
#else
#define SPINNING_TOP_FLATTEN
#endif

// SPINNING_TOP_NOINLINE keeps a function out of line even inside a flattened caller: for code that
// runs rarely (the event search inside a step) or that a flattened caller would compile worse (a
// large implicit step: gauss6's collocation inlined into the driver's step took 5.5 % more
// instructions, callgrind).
#if defined(__GNUC__) || defined(__clang__)
#define SPINNING_TOP_NOINLINE __attribute__((noinline))
#else
#define SPINNING_TOP_NOINLINE
#endif
