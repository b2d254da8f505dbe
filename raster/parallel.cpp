#include "raster/parallel.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

namespace cuberille::raster {

namespace {
std::atomic<int> gStdThreadLimit{0};
}

#if defined(CUBERILLE_PARALLEL_STD_THREADS)
int stdThreadLimit() {
    const int limit = gStdThreadLimit.load();
    return limit > 0 ? limit : int(std::max(1u, std::thread::hardware_concurrency()));
}
#endif

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
