// The tiny assertion harness shared by the C++ tests: CHECK counts passes
// and failures (printing each failure with its line), and finish() prints
// the closing "N passed, N failed" line and gives the exit code.
#pragma once

#include <cstdio>
#include <string>

namespace plumage_check {

struct Tally {
    int passed = 0;
    int failed = 0;
};

inline Tally& tally() {
    static Tally t;
    return t;
}

inline void check(bool ok, const std::string& what, int line) {
    if (ok) {
        ++tally().passed;
    } else {
        ++tally().failed;
        std::fprintf(stderr, "FAILED line %d: %s\n", line, what.c_str());
    }
}

inline int failures() { return tally().failed; }

// Prints "<name>: N passed, N failed" and returns the process exit code.
inline int finish(const std::string& name) {
    std::printf("%s: %d passed, %d failed\n", name.c_str(), tally().passed, tally().failed);
    return tally().failed == 0 ? 0 : 1;
}

}  // namespace plumage_check

#define CHECK(cond) ::plumage_check::check((cond), #cond, __LINE__)
