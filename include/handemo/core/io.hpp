// Small file helpers shared by every format: whole-file reads with clear errors and atomic writes
// (temporary file in the same directory + rename), so a crash never leaves a half-written file in place.
#pragma once

#include <handemo/core/error.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace handemo {

/// @brief Reads a whole file into a string.
/// @throws io_error naming the file when it cannot be opened or read.
inline std::string read_file(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw io_error("read_file: cannot open " + path.string());
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw io_error("read_file: read failed for " + path.string());
    return std::move(ss).str();
}

/// @brief Creates a folder and its parents (nothing when it exists).
/// @throws io_error naming the folder and the reason, never std::filesystem::filesystem_error.
inline void make_directories(const std::filesystem::path& dir)
{
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw io_error("cannot create folder " + dir.string() + ": " + ec.message());
}

namespace detail {

/// The status of `path`; a path that does not exist has type not_found.
/// @throws io_error naming the path when its status cannot be read (a folder on the way that cannot be
/// searched, a symbolic link loop, a name too long), never std::filesystem::filesystem_error.
inline std::filesystem::file_status status_of(const std::filesystem::path& path)
{
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!std::filesystem::status_known(st)) throw io_error("cannot read the status of " + path.string() + ": " + ec.message());
    return st;
}

}  // namespace detail

/// @brief Whether `path` names an existing file or folder.
/// @throws io_error naming the path when its status cannot be read (see detail::status_of()).
inline bool path_exists(const std::filesystem::path& path) { return std::filesystem::exists(detail::status_of(path)); }

/// @brief Whether `path` names an existing folder (or a link to one).
/// @throws io_error naming the path when its status cannot be read.
inline bool is_folder(const std::filesystem::path& path) { return std::filesystem::is_directory(detail::status_of(path)); }

/// @brief The regular files directly in folder `dir` (links followed), in no particular order.
/// @throws io_error naming the folder when it cannot be listed, never std::filesystem::filesystem_error.
inline std::vector<std::filesystem::path> regular_files_in(const std::filesystem::path& dir)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    std::vector<fs::path> files;
    const auto fail = [&] { return io_error("cannot list the folder " + dir.string() + ": " + ec.message()); };
    fs::directory_iterator it(dir, ec);
    if (ec) throw fail();
    for (; it != fs::directory_iterator(); it.increment(ec)) {  // an error ends the walk with ec set
        std::error_code sec;
        const auto st = it->status(sec);  // a broken link is not_found: left out, as it is no file
        if (!fs::status_known(st)) throw io_error("cannot read the status of " + it->path().string() + ": " + sec.message());
        if (fs::is_regular_file(st)) files.push_back(it->path());
    }
    if (ec) throw fail();
    return files;
}

/// @brief Writes `data` to `path` atomically: a temporary file beside it, flushed, then renamed over.
/// Either the old file or the complete new one exists at every moment.
/// @throws io_error naming the file on any failure (the temporary is removed).
inline void write_file_atomic(const std::filesystem::path& path, std::string_view data)
{
    namespace fs = std::filesystem;
    const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::error_code ec;
    if (!dir.empty() && !fs::exists(dir, ec)) fs::create_directories(dir, ec);
    std::random_device rd;
    const fs::path tmp = dir / ("." + path.filename().string() + ".tmp" + std::to_string(rd()));
    {
        std::FILE* f = std::fopen(tmp.string().c_str(), "wb");
        if (!f) throw io_error("write_file_atomic: cannot create " + tmp.string() + " for " + path.string());
        const bool ok = std::fwrite(data.data(), 1, data.size(), f) == data.size() && std::fflush(f) == 0;
        const bool closed = std::fclose(f) == 0;
        if (!ok || !closed) {
            fs::remove(tmp, ec);
            throw io_error("write_file_atomic: write failed for " + path.string());
        }
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw io_error("write_file_atomic: cannot rename into " + path.string() + ": " + ec.message());
    }
}

}  // namespace handemo
