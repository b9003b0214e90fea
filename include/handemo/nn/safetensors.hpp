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

#include <nlohmann/json.hpp>

#include <algorithm>
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace handemo {

/// @brief Element types of the safetensors format (names as written in the header).
enum class st_dtype { boolean, u8, i8, u16, i16, f16, bf16, u32, i32, f32, u64, i64, f64 };

/// @brief The header spelling of a dtype ("F32", "I64", "BOOL", ...).
inline std::string_view st_dtype_name(st_dtype t) noexcept
{
    constexpr std::string_view names[] = {"BOOL", "U8", "I8", "U16", "I16", "F16", "BF16",
                                          "U32",  "I32", "F32", "U64", "I64", "F64"};
    return names[static_cast<int>(t)];
}

/// @brief Bytes per element of a dtype.
inline std::size_t st_dtype_size(st_dtype t) noexcept
{
    constexpr std::size_t sizes[] = {1, 1, 1, 2, 2, 2, 2, 4, 4, 4, 8, 8, 8};
    return sizes[static_cast<int>(t)];
}

/// @brief Parses a header dtype string; nullopt when unknown.
inline std::optional<st_dtype> st_dtype_from_name(std::string_view s) noexcept
{
    for (int i = 0; i <= static_cast<int>(st_dtype::f64); ++i)
        if (st_dtype_name(static_cast<st_dtype>(i)) == s) return static_cast<st_dtype>(i);
    return std::nullopt;
}

/// @brief The dtype that stores C++ type T exactly (float F32, double F64, std::int64_t I64, ...).
template <class T>
constexpr st_dtype st_dtype_of() noexcept
{
    if constexpr (std::same_as<T, bool>) return st_dtype::boolean;
    else if constexpr (std::same_as<T, float>) return st_dtype::f32;
    else if constexpr (std::same_as<T, double>) return st_dtype::f64;
    else if constexpr (std::same_as<T, std::uint8_t>) return st_dtype::u8;
    else if constexpr (std::same_as<T, std::int8_t>) return st_dtype::i8;
    else if constexpr (std::same_as<T, std::uint16_t>) return st_dtype::u16;
    else if constexpr (std::same_as<T, std::int16_t>) return st_dtype::i16;
    else if constexpr (std::same_as<T, std::uint32_t>) return st_dtype::u32;
    else if constexpr (std::same_as<T, std::int32_t>) return st_dtype::i32;
    else if constexpr (std::same_as<T, std::uint64_t>) return st_dtype::u64;
    else if constexpr (std::same_as<T, std::int64_t>) return st_dtype::i64;
    else static_assert(sizeof(T) == 0, "st_dtype_of<T>: T has no safetensors dtype");
}

/// @brief Element types a tensor can be read into or written from.
template <class T>
concept st_element = std::is_arithmetic_v<T> && !std::same_as<T, char> && !std::same_as<T, long double>;

namespace detail {

template <std::unsigned_integral U>
constexpr U byte_swap(U u) noexcept
{
    U r = 0;
    for (std::size_t i = 0; i < sizeof(U); ++i) r = static_cast<U>((r << 8) | ((u >> (8 * i)) & 0xFFu));
    return r;
}

template <class U>
U load_le(const char* p) noexcept
{
    U u;
    std::memcpy(&u, p, sizeof(U));
    if constexpr (std::endian::native == std::endian::big && sizeof(U) > 1) u = byte_swap(u);
    return u;
}

template <class U>
void store_le(char* p, U u) noexcept
{
    if constexpr (std::endian::native == std::endian::big && sizeof(U) > 1) u = byte_swap(u);
    std::memcpy(p, &u, sizeof(U));
}

// IEEE binary16 -> binary32 (normals, subnormals, infinities, NaN).
inline float half_to_float(std::uint16_t h) noexcept
{
    const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
    const std::uint32_t exp = (h >> 10) & 0x1Fu;
    std::uint32_t man = h & 0x3FFu;
    std::uint32_t bits;
    if (exp == 0) {
        if (man == 0) bits = sign;
        else {  // subnormal: normalise
            int e = -1;
            do {
                man <<= 1;
                ++e;
            } while ((man & 0x400u) == 0);
            bits = sign | static_cast<std::uint32_t>(127 - 15 - e) << 23 | (man & 0x3FFu) << 13;
        }
    } else if (exp == 0x1F) bits = sign | 0x7F800000u | man << 13;
    else bits = sign | (exp + 127 - 15) << 23 | man << 13;
    return std::bit_cast<float>(bits);
}

// Reads element i of raw little-endian data of dtype t as a double (exact for every dtype but
// 64-bit integers beyond 2^53) or, for the integer target path, as the integer itself.
template <class T>
T read_element(const char* base, st_dtype t, std::size_t i) noexcept
{
    const char* p = base + i * st_dtype_size(t);
    switch (t) {
    case st_dtype::boolean: return static_cast<T>(load_le<std::uint8_t>(p) != 0);
    case st_dtype::u8: return static_cast<T>(load_le<std::uint8_t>(p));
    case st_dtype::i8: return static_cast<T>(std::bit_cast<std::int8_t>(load_le<std::uint8_t>(p)));
    case st_dtype::u16: return static_cast<T>(load_le<std::uint16_t>(p));
    case st_dtype::i16: return static_cast<T>(std::bit_cast<std::int16_t>(load_le<std::uint16_t>(p)));
    case st_dtype::f16: return static_cast<T>(half_to_float(load_le<std::uint16_t>(p)));
    case st_dtype::bf16:
        return static_cast<T>(std::bit_cast<float>(static_cast<std::uint32_t>(load_le<std::uint16_t>(p)) << 16));
    case st_dtype::u32: return static_cast<T>(load_le<std::uint32_t>(p));
    case st_dtype::i32: return static_cast<T>(std::bit_cast<std::int32_t>(load_le<std::uint32_t>(p)));
    case st_dtype::f32: return static_cast<T>(std::bit_cast<float>(load_le<std::uint32_t>(p)));
    case st_dtype::u64: return static_cast<T>(load_le<std::uint64_t>(p));
    case st_dtype::i64: return static_cast<T>(std::bit_cast<std::int64_t>(load_le<std::uint64_t>(p)));
    case st_dtype::f64: return static_cast<T>(std::bit_cast<double>(load_le<std::uint64_t>(p)));
    }
    return T{};
}

inline bool st_is_float(st_dtype t) noexcept
{
    return t == st_dtype::f16 || t == st_dtype::bf16 || t == st_dtype::f32 || t == st_dtype::f64;
}

}  // namespace detail

/// @brief One tensor of a safetensors file: name, dtype, shape and its raw little-endian bytes.
struct st_tensor {
    std::string name;
    st_dtype dtype = st_dtype::f32;
    std::vector<std::size_t> shape;
    std::string data;  ///< numel() * st_dtype_size(dtype) bytes, little-endian, row-major

    std::size_t numel() const noexcept { return shape_numel(shape); }

    /// @brief The elements converted to T (static_cast from the stored dtype; F16/BF16 decoded).
    template <st_element T>
    std::vector<T> to_vector() const
    {
        std::vector<T> out(numel());
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = detail::read_element<T>(data.data(), dtype, i);
        return out;
    }

    /// @brief Copies the elements converted to T into `out` (whose size must be numel()).
    /// @throws shape_error when the sizes differ.
    template <st_element T>
    void copy_to(std::span<T> out) const
    {
        if (out.size() != numel())
            throw shape_error("safetensors: tensor " + name + " has " + std::to_string(numel()) +
                              " elements, destination has " + std::to_string(out.size()));
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = detail::read_element<T>(data.data(), dtype, i);
    }
};

/// @brief The contents of a safetensors file: metadata and tensors (in data-offset order when read).
struct safetensors_file {
    std::map<std::string, std::string> metadata;
    std::vector<st_tensor> tensors;
    std::string source = "<memory>";  ///< file name used in error messages

    /// @brief The tensor called `name`, or nullptr.
    const st_tensor* find(std::string_view name) const noexcept
    {
        for (const auto& t : tensors)
            if (t.name == name) return &t;
        return nullptr;
    }

    /// @brief The tensor called `name`.
    /// @throws format_error naming the file and the missing tensor.
    const st_tensor& at(std::string_view name) const
    {
        if (const st_tensor* t = find(name)) return *t;
        throw format_error("safetensors: " + source + ": no tensor named " + std::string(name));
    }

    /// @brief The tensor `name` converted to T, checking its shape when `expected_shape` is given.
    /// @throws format_error when missing; shape_error naming the tensor, found and expected shape.
    template <st_element T>
    std::vector<T> get(std::string_view name, std::optional<std::vector<std::size_t>> expected_shape = {}) const
    {
        const st_tensor& t = at(name);
        if (expected_shape && *expected_shape != t.shape)
            throw shape_error("safetensors: " + source + ": tensor " + t.name + " has shape " + shape_string(t.shape) +
                              ", expected " + shape_string(*expected_shape));
        return t.to_vector<T>();
    }

    /// @brief Appends a tensor holding `values` (stored as T's dtype) with the given shape.
    /// @throws shape_error when the shape's element count differs from values.size();
    ///         value_error when the name is empty, "__metadata__" or already present.
    template <st_element T>
    st_tensor& add(std::string name, std::span<const T> values, std::vector<std::size_t> shape)
    {
        if (name.empty() || name == "__metadata__" || find(name))
            throw value_error("safetensors: " + source + ": cannot add tensor '" + name +
                              "': empty, reserved or already present");
        if (shape_numel(shape) != values.size())
            throw shape_error("safetensors: tensor " + name + ": shape " + shape_string(shape) + " holds " +
                              std::to_string(shape_numel(shape)) + " elements, given " +
                              std::to_string(values.size()));
        st_tensor t{std::move(name), st_dtype_of<T>(), std::move(shape), {}};
        t.data.resize(values.size() * sizeof(T));
        for (std::size_t i = 0; i < values.size(); ++i) {
            if constexpr (std::same_as<T, bool>) detail::store_le<std::uint8_t>(&t.data[i], values[i] ? 1 : 0);
            else if constexpr (sizeof(T) == 1) detail::store_le(&t.data[i], std::bit_cast<std::uint8_t>(values[i]));
            else if constexpr (sizeof(T) == 2) detail::store_le(&t.data[i * 2], std::bit_cast<std::uint16_t>(values[i]));
            else if constexpr (sizeof(T) == 4) detail::store_le(&t.data[i * 4], std::bit_cast<std::uint32_t>(values[i]));
            else detail::store_le(&t.data[i * 8], std::bit_cast<std::uint64_t>(values[i]));
        }
        tensors.push_back(std::move(t));
        return tensors.back();
    }

    template <st_element T>
    st_tensor& add(std::string name, const std::vector<T>& values, std::vector<std::size_t> shape)
    {
        return add<T>(std::move(name), std::span<const T>(values), std::move(shape));
    }
};

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
    if (n > 100'000'000) throw fail("header length " + std::to_string(n) + " exceeds the 100000000-byte limit");
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

/// @brief Which half of a parameter to store: its value or its gradient.
enum class param_part { value, grad };

/// @brief Adds every parameter (or gradient) of `model` as a tensor named prefix + PyTorch name.
template <parameterised M>
void add_parameters(safetensors_file& f, M& model, std::string_view prefix = "", param_part part = param_part::value)
{
    model.for_each_parameter([&]<class T>(std::string_view name, std::span<T> value, std::span<T> grad,
                                          std::span<const std::size_t> shape) {
        const std::span<T> src = part == param_part::value ? value : grad;
        f.add<std::remove_const_t<T>>(std::string(prefix) + std::string(name), std::span<const T>(src),
                                      std::vector<std::size_t>(shape.begin(), shape.end()));
    });
}

/// @brief Loads every parameter (or gradient) of `model` from the tensors named prefix + PyTorch name.
///
/// All names and shapes are checked before any value is written, so a failed load leaves the model
/// untouched. Floating dtypes (F16, BF16, F32, F64) are converted to the model's type.
/// @throws format_error listing every missing tensor and every unexpected tensor under `prefix`, or a
///         tensor of an integer dtype; shape_error naming the tensor, the found and the expected shape.
template <parameterised M>
void load_parameters(const safetensors_file& f, M& model, std::string_view prefix = "",
                     param_part part = param_part::value)
{
    std::vector<std::string> missing;
    std::set<std::string, std::less<>> used;
    model.for_each_parameter([&]<class T>(std::string_view name, std::span<T>, std::span<T>,
                                          std::span<const std::size_t> shape) {
        const std::string full = std::string(prefix) + std::string(name);
        const st_tensor* t = f.find(full);
        if (!t) {
            missing.push_back(full);
            return;
        }
        used.insert(full);
        if (!std::equal(t->shape.begin(), t->shape.end(), shape.begin(), shape.end()))
            throw shape_error("load_parameters: " + f.source + ": tensor " + full + " has shape " + shape_string(t->shape) +
                              ", expected " + shape_string(shape));
        if (!detail::st_is_float(t->dtype))
            throw format_error("load_parameters: " + f.source + ": tensor " + full + " has dtype " +
                               std::string(st_dtype_name(t->dtype)) + ", expected a floating type (F16, BF16, F32, F64)");
    });
    std::vector<std::string> extra;
    for (const auto& t : f.tensors)
        if (t.name.starts_with(prefix) && !used.contains(t.name)) extra.push_back(t.name);
    if (!missing.empty() || !extra.empty()) {
        std::string msg = "load_parameters: " + f.source + ":";
        auto list = [&](const char* what, const std::vector<std::string>& names) {
            if (names.empty()) return;
            msg += std::string(" ") + what + " (" + std::to_string(names.size()) + "):";
            for (std::size_t i = 0; i < names.size() && i < 20; ++i) msg += " " + names[i];
            if (names.size() > 20) msg += " ...";
            msg += ";";
        };
        list("missing tensors", missing);
        list("unexpected tensors", extra);
        msg.pop_back();
        throw format_error(msg);
    }
    model.for_each_parameter([&]<class T>(std::string_view name, std::span<T> value, std::span<T> grad,
                                          std::span<const std::size_t>) {
        f.at(std::string(prefix) + std::string(name)).copy_to(part == param_part::value ? value : grad);
    });
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
