#include "memory_usage.h"

#include <fstream>
#include <sstream>
#include <string>

#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
#include <malloc.h>
#define PLUMAGE_HAVE_MALLINFO2 1
#endif

namespace plumage_host {

MemoryUsage memory_usage(const PlumageSystem* sys) {
    MemoryUsage m;
    PlumageMemory held;
    plumage_memory_init(&held);
    if (sys && plumage_system_memory(sys, &held) == PLUMAGE_STATUS_OK) m.system = held;
    // Lines such as "VmRSS:	  123456 kB"; absent off Linux.
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        std::optional<uint64_t>* field = line.rfind("VmRSS:", 0) == 0 ? &m.rss_kib : line.rfind("VmHWM:", 0) == 0 ? &m.peak_rss_kib : nullptr;
        if (!field) continue;
        std::istringstream in(line.substr(6));
        uint64_t kib = 0;
        std::string unit;
        if (in >> kib >> unit && unit == "kB") *field = kib;
    }
#ifdef PLUMAGE_HAVE_MALLINFO2
    // A replaced malloc (AddressSanitizer's, for one) answers with zeros: no figure then.
    const struct mallinfo2 info = mallinfo2();
    if (info.uordblks + info.hblkhd > 0) m.heap_kib = (info.uordblks + info.hblkhd) / 1024;
#endif
    return m;
}

}  // namespace plumage_host
