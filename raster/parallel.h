#pragma once
// The one place that knows about threads. Stage code calls parallelFor over work items whose
// boundaries it chose itself (batches, tiles); results never depend on how TBB schedules them.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <memory>
#include <thread>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_scan.h>
#include <tbb/parallel_sort.h>

namespace cuberille::raster {

#if defined(CUBERILLE_PARALLEL_STD_THREADS)
/// Threads parallelFor uses in its std::thread mode (0 = hardware concurrency).
int stdThreadLimit();
#endif

/// Runs body(i) for i in [0, count), in parallel unless the thread limit is 1.
///
/// Built for ThreadSanitizer (the `tsan` preset defines CUBERILLE_PARALLEL_STD_THREADS), it runs
/// on plain std::threads taking indices from an atomic counter instead of TBB: Debian's TBB is
/// not instrumented, so TSan cannot see its synchronisation and would report every hand-off as
/// a race, drowning out real ones in our code. The work items, and so the results, are the same.
template <class Body>
void parallelFor(size_t count, Body&& body) {
#if defined(CUBERILLE_PARALLEL_STD_THREADS)
    std::atomic<size_t> next{0};
    auto worker = [&] {
        for (size_t i = next++; i < count; i = next++) body(i);
    };
    std::vector<std::thread> threads;
    const size_t extra = std::min<size_t>(count, size_t(stdThreadLimit())) - (count > 0);
    for (size_t t = 0; t < extra; ++t) threads.emplace_back(worker);
    worker();
    for (std::thread& t : threads) t.join();
#else
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) body(i);
                      });
#endif
}

/// Runs a() and b(), in parallel unless the thread limit is 1: the fork of a recursive
/// divide-and-conquer (BVH build, refit) whose halves write disjoint data. In the std::thread
/// mode (TSan) they run one after the other, for the reason parallelFor avoids TBB there.
template <class A, class B>
void parallelInvoke(A&& a, B&& b) {
#if defined(CUBERILLE_PARALLEL_STD_THREADS)
    a();
    b();
#else
    tbb::parallel_invoke(a, b);
#endif
}

/// Sorts [first, last) by less, in parallel. Keys must be unique (or equal elements identical) for
/// the result not to depend on scheduling. In the std::thread mode (TSan) it is std::sort, for the
/// same reason parallelFor avoids TBB there.
template <class It, class Less>
void parallelSort(It first, It last, Less less) {
#if defined(CUBERILLE_PARALLEL_STD_THREADS)
    std::sort(first, last, less);
#else
    tbb::parallel_sort(first, last, less);
#endif
}

/// out[i] = value(0) + ... + value(i) for i in [0, count), in parallel; returns the total. value
/// must be a pure function of i. Integer sums give the same result however the work is split.
template <class T, class Value>
T parallelInclusiveScan(size_t count, Value&& value, std::vector<T>& out) {
    out.resize(count);
#if defined(CUBERILLE_PARALLEL_STD_THREADS)
    T sum{};
    for (size_t i = 0; i < count; ++i) out[i] = sum += value(i);
    return sum;
#else
    return tbb::parallel_scan(
        tbb::blocked_range<size_t>(0, count), T{},
        [&](const tbb::blocked_range<size_t>& r, T sum, bool isFinal) {
            for (size_t i = r.begin(); i < r.end(); ++i) {
                sum += value(i);
                if (isFinal) out[i] = sum;
            }
            return sum;
        },
        [](T a, T b) { return a + b; });
#endif
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
