#pragma once
// Progress of long work on a terminal: one line on stderr, redrawn in place ("frame 3 of 12"),
// erased when the work ends. Nothing is printed when stderr is not a terminal (CI logs, pipes,
// files) or with --quiet, so captured output never holds carriage returns.

#include <string>

namespace cuberille::apps {

class ProgressLine {
public:
    /// `what`: the unit counted ("frame", "job", "setting"); `total`: how many there are.
    ProgressLine(std::string what, int total, bool quiet);
    ~ProgressLine();
    ProgressLine(const ProgressLine&) = delete;
    ProgressLine& operator=(const ProgressLine&) = delete;

    /// `done` of total finished; redraws at most every kRedrawIntervalMs (and on the last).
    void update(int done);
    /// Erases the line (before a summary goes to stdout); later updates draw nothing.
    void finish();
    bool shown() const { return shown_; }

private:
    std::string what_;
    int total_;
    bool shown_;
    double lastDrawMs_ = -1e300, startMs_;
};

}  // namespace cuberille::apps
