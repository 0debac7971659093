// The public header compiles alone as C++17 with -Wall -Wextra -Werror -pedantic.
#include "plumage.h"

static_assert(PLUMAGE_ABI_VERSION >= 1, "ABI version macro");
uint32_t plumage_header_check_cpp();
uint32_t plumage_header_check_cpp() {
    PlumageConfig cfg{};
    PlumageValidation validation{};
    (void)cfg;
    (void)validation;
    return PLUMAGE_STATUS_OK;
}
