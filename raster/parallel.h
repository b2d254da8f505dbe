#pragma once
// The one place that knows about threads. Stage code calls parallelFor over work items whose
// boundaries it chose itself (batches, tiles); results never depend on how TBB schedules them.

#include <cstddef>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace cuberille::raster {

/// Runs body(i) for i in [0, count), in parallel unless the thread limit is 1.
template <class Body>
void parallelFor(size_t count, Body&& body) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) body(i);
                      });
}

/// Caps the worker threads for its lifetime (0 = all cores). One per process at a time.
class ThreadLimit {
public:
    explicit ThreadLimit(int threads);
    ~ThreadLimit();
    ThreadLimit(const ThreadLimit&) = delete;
    ThreadLimit& operator=(const ThreadLimit&) = delete;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

int hardwareThreads();

}  // namespace cuberille::raster
