// Reader and writer of the safetensors format (Hugging Face), handemo's file format for network
// weights, optimiser state and the PyTorch golden fixtures of the StarGAN of Sec. 3.3 of the hand
// paper. No paper equation lives here. Layout: an 8-byte little-endian unsigned header length N, N
// bytes of UTF-8 JSON mapping each tensor name to {"dtype", "shape", "data_offsets": [begin, end]}
// (offsets relative to the data section) plus an optional "__metadata__" string-to-string map, then
// the data section holding every tensor's raw little-endian row-major bytes, without holes or
// overlaps. The reader checks every one of those properties and names the file and the field at
// fault; the writer pads the header with spaces to a multiple of 8 bytes (so data is 8-byte aligned,
// as the reference writer does) and writes atomically.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/nn/parameters.hpp>
#include <handemo/nn/tensor_file.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// Largest safetensors header (JSON) handemo parses: a StarGAN checkpoint's is about 10 KB.
inline constexpr std::uint64_t safetensors_max_header = std::uint64_t{4} << 20;

/// @brief Parses a safetensors image held in memory.
/// @param bytes  the whole file.
/// @param source file name for error messages.
/// @throws format_error naming `source` and the field for every violation of the format: file shorter
///         than 8 bytes, header length beyond the file, header not a JSON object or bad JSON,
///         duplicate names, unknown dtype, shape or data_offsets not arrays of non-negative integers,
///         begin > end, end beyond the data section, byte size != shape product * dtype size,
///         overlapping tensors, holes or trailing bytes in the data section, metadata not a string map.
inline safetensors_file parse_safetensors(std::string_view bytes, std::string_view source)
{
    const std::string src(source);
    auto fail = [&](const std::string& msg) -> format_error { return format_error("safetensors: " + src + ": " + msg); };
    if (bytes.size() < 8)
        throw fail("truncated file: " + std::to_string(bytes.size()) + " bytes, expected at least 8 (header length)");
    const std::uint64_t n = detail::load_le<std::uint64_t>(bytes.data());
    if (n > bytes.size() - 8)
        throw fail("header length " + std::to_string(n) + " is beyond the file (" + std::to_string(bytes.size() - 8) +
                   " bytes after the length field)");
    // nlohmann's tree takes up to ~20 times the bytes of its JSON text (a number in 2 bytes becomes a
    // 16-byte value in a growing vector), so the header is bounded before it is parsed.
    if (n > safetensors_max_header)
        throw fail("header length " + std::to_string(n) + " exceeds the " + std::to_string(safetensors_max_header) +
                   "-byte limit");
    const std::string_view header = bytes.substr(8, n);
    const std::string_view data = bytes.substr(8 + n);

    // Parse, rejecting duplicate top-level names (nlohmann would silently keep the last one).
    std::set<std::string> seen;
    std::string duplicate;
    nlohmann::json h;
    try {
        h = nlohmann::json::parse(
            header.begin(), header.end(),
            [&](int depth, nlohmann::json::parse_event_t ev, nlohmann::json& parsed) {
                if (depth > 4) throw fail("header nests JSON deeper than 4 levels");
                if (depth == 1 && ev == nlohmann::json::parse_event_t::key && parsed.is_string()) {
                    if (!seen.insert(parsed.get<std::string>()).second && duplicate.empty())
                        duplicate = parsed.get<std::string>();
                }
                return true;
            });
    } catch (const nlohmann::json::exception& e) {
        throw fail(std::string("header is not valid JSON: ") + e.what());
    }
    if (!h.is_object()) throw fail(std::string("header is a JSON ") + h.type_name() + ", expected an object");
    if (!duplicate.empty()) throw fail("tensor name " + duplicate + " appears twice in the header");

    safetensors_file f;
    f.source = src;
    struct span_info {
        std::uint64_t begin, end;
        std::size_t index;
    };
    std::vector<span_info> spans;
    for (auto it = h.begin(); it != h.end(); ++it) {
        const std::string& name = it.key();
        const nlohmann::json& e = it.value();
        if (name == "__metadata__") {
            if (!e.is_object()) throw fail(std::string("__metadata__ is a JSON ") + e.type_name() + ", expected an object");
            for (auto m = e.begin(); m != e.end(); ++m) {
                if (!m.value().is_string())
                    throw fail("__metadata__." + m.key() + " is a JSON " + m.value().type_name() + ", expected a string");
                f.metadata[m.key()] = m.value().get<std::string>();
            }
            continue;
        }
        const std::string where = "tensor " + name + ": ";
        if (!e.is_object()) throw fail(where + "entry is a JSON " + e.type_name() + ", expected an object");
        for (auto k = e.begin(); k != e.end(); ++k)
            if (k.key() != "dtype" && k.key() != "shape" && k.key() != "data_offsets")
                throw fail(where + "unknown field " + k.key() + ", expected dtype, shape, data_offsets");
        if (!e.contains("dtype") || !e["dtype"].is_string()) throw fail(where + "dtype missing or not a string");
        const std::string dts = e["dtype"].get<std::string>();
        const auto dt = st_dtype_from_name(dts);
        if (!dt)
            throw fail(where + "dtype " + dts + " is unknown, expected one of BOOL U8 I8 U16 I16 F16 BF16 U32 I32 F32 U64 I64 F64");
        if (!e.contains("shape") || !e["shape"].is_array()) throw fail(where + "shape missing or not an array");
        st_tensor t;
        t.name = name;
        t.dtype = *dt;
        std::uint64_t numel = 1;
        bool overflow = false;
        for (const auto& d : e["shape"]) {
            if (!d.is_number_unsigned()) throw fail(where + "shape entry " + d.dump() + " is not a non-negative integer");
            const std::uint64_t v = d.get<std::uint64_t>();
            if (v != 0 && numel > std::numeric_limits<std::uint64_t>::max() / v) overflow = true;
            numel *= v;
            t.shape.push_back(static_cast<std::size_t>(v));
        }
        if (!e.contains("data_offsets") || !e["data_offsets"].is_array() || e["data_offsets"].size() != 2 ||
            !e["data_offsets"][0].is_number_unsigned() || !e["data_offsets"][1].is_number_unsigned())
            throw fail(where + "data_offsets is not an array of two non-negative integers");
        const std::uint64_t b = e["data_offsets"][0].get<std::uint64_t>();
        const std::uint64_t en = e["data_offsets"][1].get<std::uint64_t>();
        if (b > en) throw fail(where + "data_offsets [" + std::to_string(b) + ", " + std::to_string(en) + "] ends before it begins");
        if (en > data.size())
            throw fail(where + "data_offsets end " + std::to_string(en) + " is beyond the data section of " +
                       std::to_string(data.size()) + " bytes (truncated file?)");
        if (overflow || numel > std::numeric_limits<std::uint64_t>::max() / st_dtype_size(*dt) ||
            numel * st_dtype_size(*dt) != en - b)
            throw fail(where + "shape " + shape_string(t.shape) + " of " + dts + " needs " +
                       (overflow ? std::string("too many") : std::to_string(numel * st_dtype_size(*dt))) +
                       " bytes, data_offsets give " + std::to_string(en - b));
        spans.push_back({b, en, f.tensors.size()});
        f.tensors.push_back(std::move(t));
    }
    std::sort(spans.begin(), spans.end(), [](const span_info& a, const span_info& b) {
        return a.begin != b.begin ? a.begin < b.begin : a.end < b.end;
    });
    std::uint64_t pos = 0;
    const st_tensor* prev = nullptr;
    for (const auto& s : spans) {
        const st_tensor& t = f.tensors[s.index];
        if (s.begin < pos)
            throw fail("tensor " + t.name + ": data_offsets [" + std::to_string(s.begin) + ", " + std::to_string(s.end) +
                       "] overlap tensor " + (prev ? prev->name : std::string("?")) + " ending at " + std::to_string(pos));
        if (s.begin > pos)
            throw fail("tensor " + t.name + ": data_offsets begin " + std::to_string(s.begin) + " leaves a hole after byte " +
                       std::to_string(pos) + " of the data section");
        pos = s.end;
        prev = &t;
    }
    if (pos != data.size())
        throw fail("data section has " + std::to_string(data.size()) + " bytes, tensors cover " + std::to_string(pos) +
                   " (trailing bytes)");
    std::vector<st_tensor> ordered;
    ordered.reserve(spans.size());
    for (const auto& s : spans) {
        st_tensor& t = f.tensors[s.index];
        t.data.assign(data.substr(s.begin, s.end - s.begin));
        ordered.push_back(std::move(t));
    }
    f.tensors = std::move(ordered);
    return f;
}

/// @brief Reads a safetensors file.
/// @throws io_error when it cannot be read; format_error as parse_safetensors.
inline safetensors_file read_safetensors(const std::filesystem::path& path)
{
    return parse_safetensors(read_file(path), path.string());
}

/// @brief Serialises to the safetensors byte layout (tensors in the given order, header padded with
/// spaces to a multiple of 8 bytes).
/// @throws value_error on a duplicate or reserved name; shape_error when a tensor's byte size does not
///         match its shape and dtype.
inline std::string serialize_safetensors(const safetensors_file& f)
{
    nlohmann::ordered_json h = nlohmann::ordered_json::object();
    if (!f.metadata.empty()) {
        nlohmann::ordered_json m = nlohmann::ordered_json::object();
        for (const auto& [k, v] : f.metadata) m[k] = v;
        h["__metadata__"] = std::move(m);
    }
    std::uint64_t offset = 0;
    for (const auto& t : f.tensors) {
        if (t.name.empty() || t.name == "__metadata__" || h.contains(t.name))
            throw value_error("safetensors: " + f.source + ": tensor name '" + t.name + "' is empty, reserved or repeated");
        if (t.data.size() != t.numel() * st_dtype_size(t.dtype))
            throw shape_error("safetensors: tensor " + t.name + ": " + std::to_string(t.data.size()) + " bytes for shape " +
                              shape_string(t.shape) + " of " + std::string(st_dtype_name(t.dtype)) + ", expected " +
                              std::to_string(t.numel() * st_dtype_size(t.dtype)));
        nlohmann::ordered_json e;
        e["dtype"] = st_dtype_name(t.dtype);
        e["shape"] = t.shape;
        e["data_offsets"] = {offset, offset + t.data.size()};
        offset += t.data.size();
        h[t.name] = std::move(e);
    }
    std::string header = h.dump();
    header.append((8 - header.size() % 8) % 8, ' ');
    std::string out(8, '\0');
    detail::store_le<std::uint64_t>(out.data(), header.size());
    out += header;
    out.reserve(out.size() + offset);
    for (const auto& t : f.tensors) out += t.data;
    return out;
}

/// @brief Writes a safetensors file atomically (temporary file + rename).
/// @throws io_error on a write failure; the errors of serialize_safetensors.
inline void write_safetensors(const std::filesystem::path& path, const safetensors_file& f)
{
    write_file_atomic(path, serialize_safetensors(f));
}

/// @brief Writes every parameter of `model` (PyTorch names) and `metadata` to a safetensors file,
/// atomically.
template <parameterised M>
void save_parameters(const std::filesystem::path& path, M& model, const std::map<std::string, std::string>& metadata = {})
{
    safetensors_file f;
    f.source = path.string();
    f.metadata = metadata;
    add_parameters(f, model);
    write_safetensors(path, f);
}

/// @brief Reads a safetensors file into every parameter of `model`; returns the file's metadata.
/// @throws io_error, format_error, shape_error as read_safetensors and load_parameters.
template <parameterised M>
std::map<std::string, std::string> load_parameters(const std::filesystem::path& path, M& model)
{
    const safetensors_file f = read_safetensors(path);
    load_parameters(f, model);
    return f.metadata;
}

}  // namespace handemo
