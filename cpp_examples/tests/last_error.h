// The library's last-error message as a std::string (sys may be NULL for
// the calling thread's last failure without a system).
#pragma once

#include <string>

#include "plumage.h"

inline std::string last_error(const PlumageSystem* sys) {
    size_t need = plumage_system_last_error(sys, nullptr, 0);
    std::string s(need, '\0');
    plumage_system_last_error(sys, s.data(), s.size());
    s.resize(need ? need - 1 : 0);
    return s;
}
