// The in-memory side of handemo's safetensors support: dtypes, one tensor's raw little-endian bytes,
// a file's tensors and metadata, typed access with conversion, and the bridge to a model's named
// parameters (add_parameters / load_parameters over for_each_parameter, PyTorch names). Parsing and
// writing files (JSON header) live in safetensors.hpp, so code that only handles tensors does not
// compile nlohmann::json. Serves the StarGAN of Sec. 3.3 of the hand paper; no paper equation here.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/half.hpp>
#include <handemo/nn/parameters.hpp>

#include <algorithm>
#include <bit>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
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

// binary16 -> binary32: handemo::half_to_float (core/half.hpp).

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

    /// @brief Refuses to read a floating-point tensor as an integer type (a hostile file could hold
    /// NaN or 1e30 where a step count or RNG state is expected, and that conversion is undefined).
    /// @throws format_error naming `source` (when given), the tensor, its dtype and the requested type.
    template <st_element T>
    void require_readable_as(std::string_view source = {}) const
    {
        if constexpr (std::is_integral_v<T> && !std::same_as<T, bool>) {
            if (detail::st_is_float(dtype))
                throw format_error("safetensors: " + (source.empty() ? std::string() : std::string(source) + ": ") +
                                   "tensor " + name + " has dtype " + std::string(st_dtype_name(dtype)) +
                                   ", expected an integer dtype to read it as " +
                                   (std::is_signed_v<T> ? "I" : "U") + std::to_string(8 * sizeof(T)));
        }
    }

    /// @brief The elements converted to T (static_cast from the stored dtype; F16/BF16 decoded).
    /// @throws format_error when T is an integer type and the dtype is floating point.
    template <st_element T>
    std::vector<T> to_vector() const
    {
        require_readable_as<T>();
        std::vector<T> out(numel());
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = detail::read_element<T>(data.data(), dtype, i);
        return out;
    }

    /// @brief Copies the elements converted to T into `out` (whose size must be numel()).
    /// @throws shape_error when the sizes differ; format_error for an integer T from a floating-point dtype.
    template <st_element T>
    void copy_to(std::span<T> out) const
    {
        require_readable_as<T>();
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
    /// @throws format_error when missing or when T is an integer type and the tensor's dtype floating point
    /// (naming the file, the tensor and both types); shape_error naming the tensor, found and expected shape.
    template <st_element T>
    std::vector<T> get(std::string_view name, std::optional<std::vector<std::size_t>> expected_shape = {}) const
    {
        const st_tensor& t = at(name);
        t.require_readable_as<T>(source);
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

}  // namespace handemo
