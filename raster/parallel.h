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
#include <tbb/task_arena.h>

namespace cuberille::raster {

/// Threads parallelFor uses when it runs on std::threads (0 = hardware concurrency).
int stdThreadLimit();

/// Whether parallel work runs on exactly the thread limit's std::threads instead of TBB: always
/// in the ThreadSanitizer build (the `tsan` preset defines CUBERILLE_PARALLEL_STD_THREADS), and
/// while an ExactThreadScheduling lives.
bool exactThreadScheduling();

/// The most threads that ran one parallelFor's work items since resetThreadsThatRan(): what
/// `--stats` reports as the threads a run used (TBB's pool never exceeds the cores, whatever
/// --threads asks for).
int threadsThatRan();
void resetThreadsThatRan();
void noteThreadsThatRan(int threads);

/// Runs body(i) for i in [0, count), in parallel unless the thread limit is 1.
///
/// On std::threads (see exactThreadScheduling) each of min(count, limit) threads takes indices
/// from an atomic counter. The ThreadSanitizer build always runs so: Debian's TBB is not
/// instrumented, so TSan cannot see its synchronisation and would report every hand-off as a
/// race, drowning out real ones in our code. The determinism tests run so to oversubscribe: TBB
/// never runs more workers than cores, so "seven threads" would mean two on this machine. The
/// work items, and so the results, are the same either way.
template <class Body>
void parallelFor(size_t count, Body&& body) {
    if (exactThreadScheduling()) {
        std::atomic<size_t> next{0};
        auto worker = [&] {
            for (size_t i = next++; i < count; i = next++) body(i);
        };
        std::vector<std::thread> threads;
        const size_t extra = std::min<size_t>(count, size_t(stdThreadLimit())) - (count > 0);
        for (size_t t = 0; t < extra; ++t) threads.emplace_back(worker);
        noteThreadsThatRan(int(extra) + 1);
        worker();
        for (std::thread& t : threads) t.join();
        return;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1), [&](const tbb::blocked_range<size_t>& r) {
        noteThreadsThatRan(tbb::this_task_arena::current_thread_index() + 1);
        for (size_t i = r.begin(); i != r.end(); ++i) body(i);
    });
}

/// Runs a() and b(), in parallel unless the thread limit is 1: the fork of a recursive
/// divide-and-conquer (BVH build, refit) whose halves write disjoint data. In the std::thread
/// mode they run one after the other, for the reason parallelFor avoids TBB there.
template <class A, class B>
void parallelInvoke(A&& a, B&& b) {
    if (exactThreadScheduling()) {
        a();
        b();
        return;
    }
    tbb::parallel_invoke(a, b);
}

/// Sorts [first, last) by less, in parallel. Keys must be unique (or equal elements identical) for
/// the result not to depend on scheduling. In the std::thread mode (TSan) it is std::sort, for the
/// same reason parallelFor avoids TBB there.
template <class It, class Less>
void parallelSort(It first, It last, Less less) {
    if (exactThreadScheduling()) {
        std::sort(first, last, less);
        return;
    }
    tbb::parallel_sort(first, last, less);
}

/// out[i] = value(0) + ... + value(i) for i in [0, count), in parallel; returns the total. value
/// must be a pure function of i. Integer sums give the same result however the work is split.
template <class T, class Value>
T parallelInclusiveScan(size_t count, Value&& value, std::vector<T>& out) {
    out.resize(count);
    if (exactThreadScheduling()) {
        T sum{};
        for (size_t i = 0; i < count; ++i) out[i] = sum += value(i);
        return sum;
    }
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

/// For its lifetime parallel work runs on exactly the thread limit's std::threads, even past
/// the core count (see parallelFor). For tests that claim a result for any thread count.
class ExactThreadScheduling {
public:
    ExactThreadScheduling();
    ~ExactThreadScheduling();
    ExactThreadScheduling(const ExactThreadScheduling&) = delete;
    ExactThreadScheduling& operator=(const ExactThreadScheduling&) = delete;

private:
    bool previous_;
};

}  // namespace cuberille::raster
