/* The public header compiles alone as C99 with -Wall -Wextra -Werror -pedantic. */
#include "plumage.h"

uint32_t plumage_header_check_c(void);
uint32_t plumage_header_check_c(void) {
    PlumageConfig cfg;
    PlumageMeshDesc mesh;
    PlumageFeather feather;
    PlumageFrameStats frame;
    (void)cfg;
    (void)mesh;
    (void)feather;
    (void)frame;
    return PLUMAGE_ABI_VERSION + PLUMAGE_STATUS_OK;
}
