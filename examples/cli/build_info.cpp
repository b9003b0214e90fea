// The one unit that includes the generated build_commit.hpp (see build_info.hpp).
#include "build_info.hpp"

#include <handemo_build_commit.hpp>

namespace handemo::cli {

const char* build_commit() noexcept { return HANDEMO_BUILD_COMMIT; }

}  // namespace handemo::cli
