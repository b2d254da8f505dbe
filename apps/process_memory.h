#pragma once
// The process's memory as the operating system counts it: what `fly --stats` reports after each
// frame and the long-run memory tests watch (docs/streaming.md, memory).

#include <cstdint>

namespace cuberille::apps {

/// Resident set size in bytes (Linux: /proc/self/statm); 0 where it cannot be read.
uint64_t residentBytes();

/// The largest resident set this program has had, in bytes (Linux: VmHWM in /proc/self/status);
/// 0 where it cannot be read. Counted from the program's start (exec), unlike the ru_maxrss a
/// parent reads from wait4, which on Linux is at least the parent's own resident set when it
/// spawned the child (a /bin/true spawned from a 400 MiB process reports 410 MiB).
uint64_t peakResidentBytes();

}  // namespace cuberille::apps
