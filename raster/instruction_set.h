#pragma once
// Which vector instruction set the back end runs on.
//
// The back end (coarse → fine → depth → shade → output merge, raster/tile_raster.cpp) is
// compiled once per instruction set with Highway's per-target pragmas, and one binary picks
// the widest path the CPU supports when it first draws. The default build names no -march:
// it runs on every x86-64 CPU. Every path computes the same values in the same order (integer
// edge functions, no fused multiply-add, no reassociated sums), so every path draws the same
// bits; the golden, exactness and determinism tests run once per path to prove it.
//
// Names: "avx512" (AVX-512 F/VL/DQ/BW, Highway's AVX3), "avx2" (with FMA and BMI2; FMA is never
// contracted into), "baseline" (what the compiler's default target has: SSE2 on x86-64, NEON
// on arm64).

#include <string>
#include <string_view>
#include <vector>

namespace cuberille::raster {

/// The instruction sets this binary was compiled for and this CPU runs, widest first.
std::vector<std::string> availableInstructionSets();

/// The instruction sets this binary was compiled for, whether or not this CPU runs them.
std::vector<std::string> compiledInstructionSets();

/// The instruction set draws run on now.
std::string activeInstructionSet();

/// Runs draws on `name` or, for "best", on the widest the CPU supports. Throws
/// std::invalid_argument naming the choices when `name` is not one of them. Call it before
/// drawing, not while another thread draws.
void useInstructionSet(std::string_view name);

/// The environment variable that chooses the instruction set for the command-line tool, the
/// tests and the benchmarks (like MKL_ENABLE_INSTRUCTIONS): unset or empty means "best".
inline constexpr const char* kInstructionSetVariable = "CUBERILLE_SIMD";

/// Applies kInstructionSetVariable when it is set; throws as useInstructionSet() does.
void useInstructionSetFromEnvironment();

}  // namespace cuberille::raster
