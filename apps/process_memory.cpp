#include "apps/process_memory.h"

#include <fstream>
#include <string>

#include <unistd.h>

namespace cuberille::apps {

uint64_t residentBytes() {
    std::ifstream statm("/proc/self/statm");
    uint64_t sizePages = 0, residentPages = 0;
    if (!(statm >> sizePages >> residentPages)) return 0;
    return residentPages * uint64_t(::sysconf(_SC_PAGESIZE));
}

uint64_t peakResidentBytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;  // "VmHWM:   123456 kB"
    return 0;
}

}  // namespace cuberille::apps
