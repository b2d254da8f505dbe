#pragma once
// Progress of long work on a terminal: one line on stderr, redrawn in place ("frame 3 of 12"),
// erased when the work ends. Nothing is printed when stderr is not a terminal (CI logs, pipes,
// files) or with --quiet, so captured output never holds carriage returns.

#include <memory>
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

/// A single piece of work that cannot count its steps (one frame): after kQuietStartMs on a
/// terminal, "rendering, 1.5 s" redrawn on stderr until it ends, then erased. Runs a thread that
/// sleeps between redraws; nothing at all when stderr is not a terminal or with --quiet.
class ElapsedLine {
public:
    ElapsedLine(std::string what, bool quiet);
    ~ElapsedLine();  // erases the line; call before printing a summary
    ElapsedLine(const ElapsedLine&) = delete;
    ElapsedLine& operator=(const ElapsedLine&) = delete;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace cuberille::apps
