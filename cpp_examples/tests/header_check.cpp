// The public header compiles alone as C++17 with -Wall -Wextra -Werror -pedantic,
// beside an engine's own names: names the header defined without the PLUMAGE_
// prefix (MAX_SEGMENTS, MAX_TRIANGLES, DEFAULT_BEND_LIMIT used to be macros)
// would clash with these, as macros defined before the include and as
// constants declared after it.
#define MAX_SEGMENTS 16
#define MAX_TRIANGLES 64
#define DEFAULT_BEND_LIMIT 1.0
#include "plumage.h"
#undef MAX_SEGMENTS
#undef MAX_TRIANGLES
#undef DEFAULT_BEND_LIMIT

namespace engine {
constexpr int MAX_SEGMENTS = 16;
constexpr int MAX_TRIANGLES = 64;
constexpr int MAX_JOINTS = 15;
constexpr int MAX_STATIONS = 16;
constexpr double DEFAULT_BEND_LIMIT = 1.0;
constexpr double DOWN_BEND_PER_LIMIT = 2.0;
constexpr double BRISTLE_TIP_HEIGHT = 0.5;
}  // namespace engine
static_assert(engine::MAX_SEGMENTS + engine::MAX_TRIANGLES + engine::MAX_JOINTS + engine::MAX_STATIONS > 0, "engine names");
static_assert(engine::DEFAULT_BEND_LIMIT + engine::DOWN_BEND_PER_LIMIT + engine::BRISTLE_TIP_HEIGHT > 0.0, "engine names");
static_assert(PLUMAGE_MAX_SHAFT_SEGMENTS == 4 && PLUMAGE_MAX_FEATHER_TRIANGLES == 14, "the header's own limits");

static_assert(PLUMAGE_ABI_VERSION >= 1, "ABI version macro");
uint32_t plumage_header_check_cpp();
uint32_t plumage_header_check_cpp() {
    PlumageConfig cfg{};
    PlumageValidation validation{};
    (void)cfg;
    (void)validation;
    return PLUMAGE_STATUS_OK;
}
