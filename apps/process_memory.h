#pragma once
// The process's memory as the operating system counts it: what `fly --stats` reports after each
// frame and the long-run memory tests watch (docs/streaming.md, memory).

#include <cstdint>

namespace cuberille::apps {

/// Resident set size in bytes (Linux: /proc/self/statm); 0 where it cannot be read.
uint64_t residentBytes();

}  // namespace cuberille::apps
