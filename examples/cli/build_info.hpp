// The commit the CLI was built from (cmake/build_commit.cmake writes it at every build; build_info.cpp is the one
// unit that includes the generated header, so a new commit recompiles that file only).
#pragma once

namespace handemo::cli {

/// @brief The source tree's git commit at build time (40 hex digits, "-dirty" when tracked files differed from it),
/// or "unknown" when the sources were not a git checkout.
const char* build_commit() noexcept;

}  // namespace handemo::cli
