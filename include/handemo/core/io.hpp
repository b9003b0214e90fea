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
