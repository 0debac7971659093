// The installed plumage.hpp compiles alone as C++17 (-Wall -Wextra -Werror -pedantic).
#include <plumage.hpp>

bool consumer_header_hpp();
bool consumer_header_hpp() { return plumage::abi_compatible(); }
