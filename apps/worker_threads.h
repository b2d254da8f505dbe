#pragma once
// The worker threads' end: a program's main holds a WorkerThreadsJoinedAtExit so that TBB's
// workers have finished before exit() runs the atexit handlers.
//
// Why: TBB releases its workers asynchronously at exit unless a task_scheduler_handle is
// finalized, so they can still be unwinding while LeakSanitizer's at-exit check stops the world
// and walks every thread's stack and TLS; a thread that disappears under it crashes the tracer
// ("Tracer caught signal 11", google/sanitizers#1353), failing a run whose work succeeded. It
// is also the tidy end for any program: no thread of ours outlives main.

#include <new>

#include <oneapi/tbb/global_control.h>

namespace cuberille::apps {

class WorkerThreadsJoinedAtExit {
public:
    WorkerThreadsJoinedAtExit() : handle_(oneapi::tbb::attach{}) {}
    // Blocks until the workers have ended; returns false (and lets them go as before) when an
    // arena or a global_control is still alive, which a main's last local never sees.
    ~WorkerThreadsJoinedAtExit() { (void)oneapi::tbb::finalize(handle_, std::nothrow); }
    WorkerThreadsJoinedAtExit(const WorkerThreadsJoinedAtExit&) = delete;
    WorkerThreadsJoinedAtExit& operator=(const WorkerThreadsJoinedAtExit&) = delete;

private:
    oneapi::tbb::task_scheduler_handle handle_;
};

}  // namespace cuberille::apps
