#include "raster/parallel.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

namespace cuberille::raster {

namespace {
std::atomic<int> gStdThreadLimit{0};
#if defined(CUBERILLE_PARALLEL_STD_THREADS)
std::atomic<bool> gExactThreads{true};
#else
std::atomic<bool> gExactThreads{false};
#endif
std::atomic<int> gThreadsThatRan{0};
}  // namespace

int stdThreadLimit() {
    const int limit = gStdThreadLimit.load();
    return limit > 0 ? limit : int(std::max(1u, std::thread::hardware_concurrency()));
}

bool exactThreadScheduling() { return gExactThreads.load(std::memory_order_relaxed); }

int threadsThatRan() { return gThreadsThatRan.load(); }
void resetThreadsThatRan() { gThreadsThatRan.store(0); }
void noteThreadsThatRan(int threads) {
    int seen = gThreadsThatRan.load(std::memory_order_relaxed);
    while (threads > seen && !gThreadsThatRan.compare_exchange_weak(seen, threads, std::memory_order_relaxed)) {
    }
}

ExactThreadScheduling::ExactThreadScheduling() : previous_(gExactThreads.exchange(true)) {}
ExactThreadScheduling::~ExactThreadScheduling() {
#if defined(CUBERILLE_PARALLEL_STD_THREADS)
    (void)previous_;  // the ThreadSanitizer build stays on std::threads
#else
    gExactThreads.store(previous_);
#endif
}

struct ThreadLimit::Impl {
    std::unique_ptr<tbb::global_control> control;
    int previousStdLimit = 0;
};

ThreadLimit::ThreadLimit(int threads) : impl_(std::make_unique<Impl>()) {
    impl_->previousStdLimit = gStdThreadLimit.exchange(threads);
    if (threads > 0) {
        impl_->control = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
    }
}

ThreadLimit::~ThreadLimit() { gStdThreadLimit.store(impl_->previousStdLimit); }

int hardwareThreads() { return tbb::info::default_concurrency(); }

}  // namespace cuberille::raster
