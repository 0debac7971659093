/* The installed plumage.h compiles alone as C99 (-Wall -Wextra -Werror -pedantic). */
#include <plumage.h>

uint32_t consumer_header_c99(void);
uint32_t consumer_header_c99(void) {
    PlumageConfig cfg;
    PlumageFeatherGeometry geometry;
    PlumageValidation validation;
    (void)cfg;
    (void)geometry;
    (void)validation;
    return PLUMAGE_ABI_VERSION + PLUMAGE_STATUS_OK;
}
