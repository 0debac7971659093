// The host's failure kinds; main() maps each one to an exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace plumage_host {

// The command line is wrong (exit 2).
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// The input file cannot be read or uses something the host does not support (exit 3).
struct InputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// An output file cannot be written (exit 1).
struct OutputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace plumage_host
