#pragma once
// The thread counts a "same result for any thread count" test runs: one and two threads on TBB's
// pool, and seven on exactly seven std::threads, more than the cores of the machines CI runs on.
// TBB never runs more workers than cores, so asking it for seven would run two here, and a test
// named for seven threads would check two (raster/parallel.h, ExactThreadScheduling).

#include <optional>

#include "raster/parallel.h"

namespace cuberille::testing {

struct ThreadCount {
    int threads;
    bool exact;  // on exactly `threads` std::threads, whatever the cores
};
inline constexpr ThreadCount kThreadCounts[] = {{1, false}, {2, false}, {7, true}};

/// For its lifetime work runs on the count's threads; ran() says how many ran one step at most.
class ThreadCountScope {
public:
    explicit ThreadCountScope(ThreadCount count) : limit_(count.threads) {
        if (count.exact) exact_.emplace();
        raster::resetThreadsThatRan();
    }
    int ran() const { return raster::threadsThatRan(); }

private:
    raster::ThreadLimit limit_;
    std::optional<raster::ExactThreadScheduling> exact_;
};

}  // namespace cuberille::testing
