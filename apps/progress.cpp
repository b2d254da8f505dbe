#include "apps/progress.h"

#include <cstdio>
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

}  // namespace cuberille::apps
