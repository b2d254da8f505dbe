#include "apps/progress.h"

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <unistd.h>

#include "raster/clock.h"

namespace cuberille::apps {
namespace {

// Redraws are for a person watching, not a log: four a second reads as live and costs nothing
// beside frames that take milliseconds.
constexpr double kRedrawIntervalMs = 250.0;

}  // namespace

ProgressLine::ProgressLine(std::string what, int total, bool quiet)
    : what_(std::move(what)), total_(total), shown_(!quiet && total > 1 && isatty(STDERR_FILENO)), startMs_(raster::nowMs()) {}

ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::finish() {
    if (shown_ && lastDrawMs_ > -1e300) std::fprintf(stderr, "\r\033[K");  // erase the line
    shown_ = false;
}

void ProgressLine::update(int done) {
    if (!shown_) return;
    const double now = raster::nowMs();
    if (now - lastDrawMs_ < kRedrawIntervalMs && done < total_) return;
    lastDrawMs_ = now;
    const double elapsedS = (now - startMs_) / 1000.0;
    const double leftS = done > 0 ? elapsedS * double(total_ - done) / double(done) : 0.0;
    std::fprintf(stderr, "\r\033[K%s %d of %d, %.1f s, about %.0f s left", what_.c_str(), done, total_, elapsedS, leftS);
    std::fflush(stderr);
}

namespace {

// Work shorter than this shows nothing ("renders over a second"); CUBERILLE_PROGRESS_AFTER_MS
// changes it (the tests set 0 to see the line on any machine).
constexpr double kQuietStartMs = 1000.0;

double quietStartMs() {
    const char* text = std::getenv("CUBERILLE_PROGRESS_AFTER_MS");
    if (!text || !*text) return kQuietStartMs;
    char* end = nullptr;
    const double ms = std::strtod(text, &end);
    return end && *end == '\0' && ms >= 0.0 ? ms : kQuietStartMs;
}

}  // namespace

struct ElapsedLine::Impl {
    std::string what;
    std::mutex mutex;
    std::condition_variable stopped;
    bool stop = false, drawn = false;
    std::thread thread;
};

ElapsedLine::ElapsedLine(std::string what, bool quiet) {
    if (quiet || !isatty(STDERR_FILENO)) return;
    impl_ = std::make_unique<Impl>();
    impl_->what = std::move(what);
    impl_->thread = std::thread([impl = impl_.get()] {
        const double start = raster::nowMs();
        std::unique_lock lock(impl->mutex);
        double wait = quietStartMs();
        while (!impl->stopped.wait_for(lock, std::chrono::duration<double, std::milli>(wait), [&] { return impl->stop; })) {
            std::fprintf(stderr, "\r\033[K%s, %.1f s", impl->what.c_str(), (raster::nowMs() - start) / 1000.0);
            std::fflush(stderr);
            impl->drawn = true;
            wait = kRedrawIntervalMs;
        }
        if (impl->drawn) std::fprintf(stderr, "\r\033[K");
    });
}

ElapsedLine::~ElapsedLine() {
    if (!impl_) return;
    {
        std::lock_guard lock(impl_->mutex);
        impl_->stop = true;
    }
    impl_->stopped.notify_one();
    impl_->thread.join();
}

}  // namespace cuberille::apps
