#include "raster/parallel.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

namespace cuberille::raster {

struct ThreadLimit::Impl {
    std::unique_ptr<tbb::global_control> control;
};

ThreadLimit::ThreadLimit(int threads) : impl_(std::make_unique<Impl>()) {
    if (threads > 0) {
        impl_->control = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, static_cast<size_t>(threads));
    }
}

ThreadLimit::~ThreadLimit() = default;

int hardwareThreads() { return tbb::info::default_concurrency(); }

}  // namespace cuberille::raster
