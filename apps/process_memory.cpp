#include "apps/process_memory.h"

#include <fstream>

#include <unistd.h>

namespace cuberille::apps {

uint64_t residentBytes() {
    std::ifstream statm("/proc/self/statm");
    uint64_t sizePages = 0, residentPages = 0;
    if (!(statm >> sizePages >> residentPages)) return 0;
    return residentPages * uint64_t(::sysconf(_SC_PAGESIZE));
}

}  // namespace cuberille::apps
