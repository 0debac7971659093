// The installed plumage.h compiles alone as C++17 (-Wall -Wextra -Werror -pedantic).
#include <plumage.h>

uint32_t consumer_header_cxx17();
uint32_t consumer_header_cxx17() {
    PlumageFrameStats stats{};
    return PLUMAGE_ABI_VERSION + stats.struct_size;
}
