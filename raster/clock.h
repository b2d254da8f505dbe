#pragma once
// The one clock stage timings are read from: a steady clock in milliseconds, for `--stats` and
// the benchmarks (never for anything a result depends on).

#include <chrono>

namespace cuberille::raster {

inline double nowMs() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace cuberille::raster
