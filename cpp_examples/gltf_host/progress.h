// Wall-clock timing and the progress line shown on a terminal.
#pragma once

#include <chrono>
#include <cstdio>
#include <unistd.h>

namespace plumage_host {

class Stopwatch {
public:
    double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// "frame k/N" on stderr, redrawn at most ten times a second, only when
// stderr is a terminal and the run has lasted more than a second.
class ProgressLine {
public:
    ProgressLine() : enabled_(isatty(STDERR_FILENO) != 0) {}
    ProgressLine(const ProgressLine&) = delete;
    ProgressLine& operator=(const ProgressLine&) = delete;
    ~ProgressLine() { clear(); }

    void update(size_t done, size_t total, double step_seconds) {
        const double now = clock_.seconds();
        if (!enabled_ || now < 1.0 || now - last_draw_ < 0.1) return;
        last_draw_ = now;
        std::fprintf(stderr, "\rplumage_gltf: frame %zu/%zu  step %.2f ms ", done, total, step_seconds * 1e3);
        std::fflush(stderr);
        drawn_ = true;
    }

    void clear() {
        if (!drawn_) return;
        std::fprintf(stderr, "\r\033[K");
        std::fflush(stderr);
        drawn_ = false;
    }

private:
    bool enabled_;
    bool drawn_ = false;
    double last_draw_ = 0;
    Stopwatch clock_;
};

}  // namespace plumage_host
