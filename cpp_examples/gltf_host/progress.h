// Wall-clock timing and the progress line shown on a terminal.
#pragma once

#include "plumage.h"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace plumage_host {

class Stopwatch {
public:
    double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

private:
    std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// One line on stderr ("frame 12/480: adjusting 40%"), redrawn at most ten
// times a second, only when stderr is a terminal and the run has lasted
// more than a second. The library reports its phases through
// `library_callback` (PlumageConfig.progress), from whichever thread it
// likes but never two at once, while the host waits inside the call.
class ProgressLine {
public:
    ProgressLine() : enabled_(isatty(STDERR_FILENO) != 0) {}
    ProgressLine(const ProgressLine&) = delete;
    ProgressLine& operator=(const ProgressLine&) = delete;
    ~ProgressLine() { clear(); }

    // What the next library call works on, e.g. "rest pose" or "frame 3/60".
    void set_context(std::string context) { context_ = std::move(context); }

    void frame_done(size_t done, size_t total, double step_seconds) {
        char text[96];
        std::snprintf(text, sizeof text, "frame %zu/%zu  step %.2f ms", done, total, step_seconds * 1e3);
        draw(text);
    }

    static int32_t library_callback(void* self, uint32_t phase, float fraction) noexcept {
        static_cast<ProgressLine*>(self)->library_phase(phase, fraction);
        return 0;  // never interrupts
    }

    void clear() {
        if (!drawn_) return;
        std::fprintf(stderr, "\r\033[K");
        std::fflush(stderr);
        drawn_ = false;
    }

private:
    void library_phase(uint32_t phase, float fraction) {
        static const char* const kPhases[] = {"preparing", "sampling", "ordering", "adjusting", "validating"};
        char text[160];
        std::snprintf(text, sizeof text, "%s: %s %3.0f%%", context_.c_str(), phase < sizeof kPhases / sizeof kPhases[0] ? kPhases[phase] : "working", fraction * 100.0);
        draw(text);
    }

    void draw(const char* text) {
        const double now = clock_.seconds();
        if (!enabled_ || now < 1.0 || now - last_draw_ < 0.1) return;
        last_draw_ = now;
        std::fprintf(stderr, "\r\033[Kplumage_gltf: %s", text);
        std::fflush(stderr);
        drawn_ = true;
    }

    bool enabled_;
    bool drawn_ = false;
    double last_draw_ = 0;
    std::string context_ = "working";
    Stopwatch clock_;
};

}  // namespace plumage_host
