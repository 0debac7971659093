// The host process's memory, read in-process: resident set size now and at
// its peak (Linux: VmRSS and VmHWM of /proc/self/status) and the bytes the
// allocator has handed out and not taken back (glibc: mallinfo2). The
// library allocates through the same malloc, so both cover it and the host.
// A figure the platform does not give is left empty, and so is the heap
// under a malloc that does not fill mallinfo2 (AddressSanitizer's).
#pragma once

#include <plumage.h>

#include <cstdint>
#include <optional>

namespace plumage_host {

struct MemoryUsage {
    std::optional<uint64_t> rss_kib;       // resident now
    std::optional<uint64_t> peak_rss_kib;  // highest resident so far
    std::optional<uint64_t> heap_kib;      // live heap: in-use arena chunks plus mmapped blocks
    std::optional<PlumageMemory> system;   // what the library's system holds (plumage_system_memory)
};

// The process's figures, and with `sys` the system's own.
MemoryUsage memory_usage(const PlumageSystem* sys = nullptr);

}  // namespace plumage_host
