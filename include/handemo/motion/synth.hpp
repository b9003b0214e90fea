// The synthetic hand-motion emotion dataset. No hand-motion emotion data can be downloaded (the paper's
// Senso-glove database, Section 3.1, was never released), so handemo generates one that follows the
// paper's protocol: 7 motion types x 5 emotions, each take exactly 2 cycles (Section 3.2), on the 23-joint
// hand (Eq. 1), with Table 1's characteristics. Every motion type is its own movement, built from per-joint
// tracks (base pose + amplitude x periodic waveform + phase) on distinct joint groups:
//   crawling      index..pinky walk in sequence (MCP/PIP/DIP sine, 0.22-cycle lag per finger), wrist flexed
//   gripping      all fingers and the thumb flex together into a fist and open (plateau wave)
//   patting       wrist lifts slowly (extension) and pats down fast, fingers flat and trailing
//   impatient     fingers resting on a surface tap in sequence pinky -> index (narrow pulses)
//   hand-on-mouse hand resting curved, small index and middle clicks half a cycle apart, wrist sway
//   pointing      index extended, the others curled, the wrist and forearm moving the pointer
//   pushing       wrist extension with straight spread fingers, forearm swing and root translation
// The extended set (motion_set::extended, `handemo synth --motion-set extended`) adds five, 12 in all:
//   waving        forearm raised, the wrist sweeping side to side, spread fingers trailing
//   counting      from a fist, thumb .. pinky extend one after another (0.12 cycle apart), then close
//   scratching    the four fingers flex quickly together (0.7 s cycles), the wrist flexed and still
//   piano         presses thumb .. pinky in sequence on an arched, pronated hand (narrow pulses)
//   beckoning     palm up, index and middle curl in and out, the others curled
// Emotion styles (ground truth for later evaluation, returned by style_of()):
//
// | emotion | tempo | amplitude | sharpness | finger lag (cycles) | tremor (deg @ Hz) | noise (deg) | droop (deg) | bounce (deg) |
// |---------|-------|-----------|-----------|---------------------|-------------------|-------------|-------------|--------------|
// | angry   | 1.60  | 1.45      | 1.8       | 0                   | 0                 | 0.6         | 0           | 0            |
// | happy   | 1.30  | 1.30      | 1.2       | 0                   | 0                 | 0.4         | -4          | 5            |
// | neutral | 1.00  | 1.00      | 1.0       | 0                   | 0                 | 0.3         | 0           | 0            |
// | sad     | 0.60  | 0.55      | 0.7       | 0                   | 0                 | 0.3         | 12          | 0            |
// | fearful | 1.15  | 0.60      | 1.0       | 0.09 per finger     | 1.0 @ 9 Hz        | 0.5         | 4           | 0            |
//
// tempo multiplies the cycle rate (duration = 2 neutral periods / tempo); amplitude scales every excursion
// about the base pose; sharpness s reshapes each waveform value w as |w|^(1/s) (s > 1 snappier, held
// extremes: exaggerated; s < 1 softer, tired); finger lag delays finger k (thumb 0 .. pinky 4) by
// k x lag cycles in a per-take direction (asynchronous fingers); tremor is a per-finger sinusoid on
// flexion; noise is smooth (three random sinusoids of 0.3-1.5 Hz per channel); droop adds wrist and half
// as much MCP/PIP flexion (tired, sinking hand; negative = lifted); bounce is a second-harmonic wrist
// flexion (energetic). Per take (seeded): tempo x U(0.93, 1.07), amplitude x U(0.9, 1.1) and per track
// x U(0.95, 1.05), start phase U(-0.03, 0.03) cycles, base pose + N(0, 2) deg per track. Every angle is
// clamped into the joint's limits. Neutral periods: crawling 1.5 s, gripping 1.6, patting 1.0, impatient
// 1.2, hand-on-mouse 1.1, pointing 1.8, pushing 1.7 (neutral clips 2.0-3.6 s). Deterministic for a seed:
// std::mt19937_64 with handemo's own uniform/normal transforms (detail/synth_random.hpp).
// The extended set's types show the emotions differently (style_of(motion, emotion), expression_of()): the
// table's tempo and amplitude factors are raised to a per-motion power, its droop, tremor and finger lag scaled:
//
// | motion     | neutral period (s) | tempo power | amplitude power | droop x | tremor x | finger lag x |
// |------------|--------------------|-------------|-----------------|---------|----------|--------------|
// | waving     | 1.3                | 1.0         | 1.3             | 0.5     | 1.0      | 0.5          |
// | counting   | 2.4                | 0.6         | 0.6             | 1.0     | 1.0      | 2.0          |
// | scratching | 0.7                | 1.2         | 1.0             | 1.0     | 1.5      | 1.0          |
// | piano      | 1.6                | 1.0         | 1.2             | 0.5     | 1.0      | 1.5          |
// | beckoning  | 1.2                | 1.0         | 1.0             | 1.5     | 0.5      | 0.5          |
//
// The paper's seven types use the table as it is, so the 7-type set is the same files for the same seed and
// options as before the extended set existed (a test hashes them).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/detail/synth_random.hpp>
#include <handemo/motion/hand.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// The five emotions of the paper (Table 1).
enum class emotion : std::uint8_t { angry, happy, neutral, sad, fearful };
inline constexpr std::size_t emotion_count = 5;
inline constexpr std::array<emotion, 5> all_emotions{emotion::angry, emotion::happy, emotion::neutral, emotion::sad,
                                                     emotion::fearful};

/// The hand motion types: the seven of the paper (Section 3.1), then the five of the extended set.
enum class hand_motion : std::uint8_t {
    crawling, gripping, patting, impatient, hand_on_mouse, pointing, pushing,  // the paper's
    waving, counting, scratching, piano, beckoning                              // the extended set's
};
/// The paper's seven motion types (the default set).
inline constexpr std::size_t hand_motion_count = 7;
inline constexpr std::array<hand_motion, 7> all_hand_motions{hand_motion::crawling,  hand_motion::gripping,
                                                             hand_motion::patting,   hand_motion::impatient,
                                                             hand_motion::hand_on_mouse, hand_motion::pointing,
                                                             hand_motion::pushing};
/// The twelve motion types of the extended set: the paper's seven, then five more.
inline constexpr std::size_t extended_hand_motion_count = 12;
inline constexpr std::array<hand_motion, 12> extended_hand_motions{
    hand_motion::crawling, hand_motion::gripping, hand_motion::patting,  hand_motion::impatient,
    hand_motion::hand_on_mouse, hand_motion::pointing, hand_motion::pushing, hand_motion::waving,
    hand_motion::counting, hand_motion::scratching, hand_motion::piano,  hand_motion::beckoning};

/// @brief Which motion types a synthetic set holds: the paper's 7 or the extended 12.
enum class motion_set : std::uint8_t { paper, extended };

/// @brief The motion types of a set, in order.
inline std::vector<hand_motion> motions_of(motion_set s)
{
    if (s == motion_set::extended) return {extended_hand_motions.begin(), extended_hand_motions.end()};
    return {all_hand_motions.begin(), all_hand_motions.end()};
}

/// @brief Lower-case name: angry, happy, neutral, sad, fearful.
constexpr std::string_view to_string(emotion e) noexcept
{
    constexpr std::string_view n[] = {"angry", "happy", "neutral", "sad", "fearful"};
    return n[static_cast<int>(e)];
}

/// @brief Name as used in file names: crawling, gripping, patting, impatient, hand-on-mouse, pointing, pushing,
/// waving, counting, scratching, piano, beckoning.
constexpr std::string_view to_string(hand_motion m) noexcept
{
    constexpr std::string_view n[] = {"crawling", "gripping", "patting",  "impatient",  "hand-on-mouse", "pointing",
                                      "pushing",  "waving",   "counting", "scratching", "piano",         "beckoning"};
    return n[static_cast<int>(m)];
}

/// @brief The name of a motion set: paper or extended.
constexpr std::string_view to_string(motion_set s) noexcept { return s == motion_set::extended ? "extended" : "paper"; }

/// @brief Parses a motion set name (paper, extended).
/// @throws value_error naming the text and the valid names.
inline motion_set motion_set_from_string(std::string_view s)
{
    if (s == "paper") return motion_set::paper;
    if (s == "extended") return motion_set::extended;
    throw value_error("motion set: unknown set '" + std::string(s) + "', expected paper (7 motion types) or extended (12)");
}

/// @brief Parses an emotion name (exact, lower case).
/// @throws value_error naming the text and the valid names.
inline emotion emotion_from_string(std::string_view s)
{
    for (emotion e : all_emotions)
        if (to_string(e) == s) return e;
    throw value_error("emotion: unknown emotion '" + std::string(s) + "', expected angry, happy, neutral, sad or fearful");
}

/// @brief Parses a motion name; `hand_on_mouse` is accepted for `hand-on-mouse`.
/// @throws value_error naming the text and the valid names.
inline hand_motion hand_motion_from_string(std::string_view s)
{
    if (s == "hand_on_mouse") return hand_motion::hand_on_mouse;
    for (hand_motion m : extended_hand_motions)
        if (to_string(m) == s) return m;
    throw value_error("hand_motion: unknown motion '" + std::string(s) +
                      "', expected crawling, gripping, patting, impatient, hand-on-mouse, pointing, pushing, waving, "
                      "counting, scratching, piano or beckoning");
}

/// @brief The generator parameters of one emotion (see the table in this header's comment).
struct emotion_style {
    double tempo;       ///< cycle-rate factor; duration = 2 neutral periods / tempo
    double amplitude;   ///< excursion factor about the base pose (range of motion)
    double sharpness;   ///< waveform exponent 1/s applied to |w|
    double phase_lag;   ///< per-finger phase lag in cycles (asynchrony)
    double tremor_deg;  ///< tremor amplitude on finger and wrist flexion
    double tremor_hz;   ///< tremor frequency
    double noise_deg;   ///< smooth noise amplitude on every rotation channel
    double droop_deg;   ///< added wrist flexion (half on MCP/PIP); negative lifts
    double bounce_deg;  ///< second-harmonic wrist flexion
};

/// @brief The ground-truth style parameters of an emotion.
constexpr emotion_style style_of(emotion e) noexcept
{
    switch (e) {
    case emotion::angry: return {1.60, 1.45, 1.8, 0.00, 0.0, 0.0, 0.6, 0.0, 0.0};
    case emotion::happy: return {1.30, 1.30, 1.2, 0.00, 0.0, 0.0, 0.4, -4.0, 5.0};
    case emotion::sad: return {0.60, 0.55, 0.7, 0.00, 0.0, 0.0, 0.3, 12.0, 0.0};
    case emotion::fearful: return {1.15, 0.60, 1.0, 0.09, 1.0, 9.0, 0.5, 4.0, 0.0};
    default: return {1.00, 1.00, 1.0, 0.00, 0.0, 0.0, 0.3, 0.0, 0.0};
    }
}

/// @brief How strongly a motion type shows each emotion effect (the extended set's table in this header's
/// comment): the style's tempo and amplitude factors are raised to `tempo` and `amplitude`, its droop, tremor and
/// finger lag multiplied by `droop`, `tremor` and `lag`. The paper's seven types show every effect as style_of(e)
/// gives it (all 1).
struct expression_gains {
    double tempo = 1, amplitude = 1, droop = 1, tremor = 1, lag = 1;
};

/// @brief The expression gains of a motion type (see expression_gains).
constexpr expression_gains expression_of(hand_motion m) noexcept
{
    switch (m) {
    case hand_motion::waving: return {1.0, 1.3, 0.5, 1.0, 0.5};
    case hand_motion::counting: return {0.6, 0.6, 1.0, 1.0, 2.0};
    case hand_motion::scratching: return {1.2, 1.0, 1.0, 1.5, 1.0};
    case hand_motion::piano: return {1.0, 1.2, 0.5, 1.0, 1.5};
    case hand_motion::beckoning: return {1.0, 1.0, 1.5, 0.5, 0.5};
    default: return {};
    }
}

/// @brief The style an emotion has on a motion type: style_of(e) for the paper's seven (bit for bit), and for
/// the extended set's types style_of(e) with the motion's expression_of() gains applied.
inline emotion_style style_of(hand_motion m, emotion e) noexcept
{
    emotion_style s = style_of(e);
    if (static_cast<std::size_t>(m) < hand_motion_count) return s;
    const expression_gains g = expression_of(m);
    s.tempo = std::pow(s.tempo, g.tempo);
    s.amplitude = std::pow(s.amplitude, g.amplitude);
    s.droop_deg *= g.droop;
    s.tremor_deg *= g.tremor;
    s.phase_lag *= g.lag;
    return s;
}

/// @brief Seconds per cycle of a motion type performed neutrally (before per-take variation).
constexpr double neutral_period(hand_motion m) noexcept
{
    constexpr double p[] = {1.5, 1.6, 1.0, 1.2, 1.1, 1.8, 1.7, 1.3, 2.4, 0.7, 1.6, 1.2};
    return p[static_cast<int>(m)];
}

/// Number of cycles every take performs (Section 3.2: "exactly 2 cycles").
inline constexpr int synth_cycles = 2;

namespace detail {

enum class wave : std::uint8_t { sine, raised, pulse, plateau, pat };

/// One generator track: channel value += base + amp * shape(wave(phase_cycles - phase)).
struct motion_track {
    std::size_t joint;
    std::size_t axis;       ///< 0 x, 1 y, 2 z rotation; 3..5 = x, y, z translation of the root
    double base;
    double amp;
    wave w;
    double phase;           ///< cycles
    int finger;             ///< 0..4 when the finger lag applies, -1 otherwise
    double width;           ///< pulse width in cycles
};

inline double smoothstep(double x) noexcept
{
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}


/// Periodic waveform of period 1: sine in [-1, 1], the others in [0, 1] starting at 0.
inline double wave_value(wave w, double phi, double width) noexcept
{
    const double p = phi - std::floor(phi);
    constexpr double tau = 2.0 * std::numbers::pi;
    switch (w) {
    case wave::sine: return std::sin(tau * p);
    case wave::raised: return 0.5 - 0.5 * std::cos(tau * p);
    case wave::pulse: return p < width ? 0.5 - 0.5 * std::cos(tau * p / width) : 0.0;
    case wave::plateau:  // close 0..0.35, hold, open 0.5..0.85, hold open
        if (p < 0.35) return smoothstep(p / 0.35);
        if (p < 0.5) return 1.0;
        if (p < 0.85) return 1.0 - smoothstep((p - 0.5) / 0.35);
        return 0.0;
    default:  // pat: slow lift 0..0.7, fast drop 0.7..1
        return p < 0.7 ? smoothstep(p / 0.7) : 1.0 - smoothstep((p - 0.7) / 0.3);
    }
}

inline double shape(double v, double sharpness) noexcept
{
    const double a = std::pow(std::abs(v), 1.0 / sharpness);
    return v < 0 ? -a : a;
}

/// The tracks of one motion type (see the header comment).
inline std::vector<motion_track> motion_tracks(hand_motion m)
{
    using hand_index::finger_joint;
    constexpr std::size_t F = hand_index::forearm, W = hand_index::wrist, P = hand_index::palm;
    constexpr std::size_t x = 0, y = 1, z = 2;
    std::vector<motion_track> t;
    auto add = [&](std::size_t j, std::size_t a, double base, double amp, wave w, double phase, int finger,
                   double width = 0.2) { t.push_back({j, a, base, amp, w, phase, finger, width}); };
    auto pose = [&](std::size_t j, std::size_t a, double base) { add(j, a, base, 0.0, wave::sine, 0.0, -1); };
    constexpr double spread[5] = {0, -5, 0, 4, 7};  // MCP abduction at rest (index toward +X)
    switch (m) {
    case hand_motion::crawling:
        for (int f = 1; f < 5; ++f) {
            const double seq = 0.22 * (f - 1);
            add(finger_joint(f, 1), x, 30, 25, wave::sine, seq, f);
            add(finger_joint(f, 2), x, 50, 28, wave::sine, seq + 0.2, f);
            add(finger_joint(f, 3), x, 25, 15, wave::sine, seq + 0.25, f);
            pose(finger_joint(f, 1), z, spread[f]);
        }
        add(finger_joint(0, 2), x, 20, 10, wave::sine, 0.5, 0);
        pose(finger_joint(0, 1), z, -15);
        pose(W, x, 25);  // hand arched over the table
        add(W, z, 0, 4, wave::sine, 0.0, -1);
        pose(F, z, 10);
        add(F, x, 0, 3, wave::sine, 0.1, -1);
        break;
    case hand_motion::gripping:
        for (int f = 1; f < 5; ++f) {
            add(finger_joint(f, 1), x, 5, 50, wave::plateau, 0.0, f);
            add(finger_joint(f, 2), x, 5, 60, wave::plateau, 0.02, f);
            add(finger_joint(f, 3), x, 3, 40, wave::plateau, 0.04, f);
            add(finger_joint(f, 1), z, spread[f], -0.8 * spread[f], wave::plateau, 0.0, f);
        }
        add(finger_joint(3, 0), x, 0, 4, wave::plateau, 0.0, 3);
        add(finger_joint(4, 0), x, 0, 8, wave::plateau, 0.0, 4);
        add(finger_joint(0, 1), x, 0, 25, wave::plateau, 0.03, 0);
        pose(finger_joint(0, 1), z, -10);
        add(finger_joint(0, 2), x, 0, 33, wave::plateau, 0.05, 0);
        add(finger_joint(0, 3), x, 0, 40, wave::plateau, 0.07, 0);
        pose(W, x, 5);
        pose(W, z, -10);
        pose(F, y, 35);  // semi-supinated, as when holding a handle
        break;
    case hand_motion::patting:
        add(W, x, 10, -35, wave::pat, 0.0, -1);
        add(F, x, 0, -6, wave::pat, 0.0, -1);
        add(P, x, 0, -3, wave::pat, 0.03, -1);
        for (int f = 1; f < 5; ++f) {
            add(finger_joint(f, 1), x, 5, -8, wave::pat, 0.06, f);
            pose(finger_joint(f, 2), x, 5);
            pose(finger_joint(f, 3), x, 3);
            pose(finger_joint(f, 1), z, spread[f] * 0.8);
        }
        pose(finger_joint(0, 1), z, -20);
        pose(finger_joint(0, 2), x, 5);
        break;
    case hand_motion::impatient:
        for (int f = 1; f < 5; ++f) {
            const double seq = 0.14 * (4 - f);  // pinky first, index last
            add(finger_joint(f, 1), x, 40, -30, wave::pulse, seq, f, 0.22);
            add(finger_joint(f, 2), x, 35, -15, wave::pulse, seq + 0.02, f, 0.22);
            add(finger_joint(f, 3), x, 15, -8, wave::pulse, seq + 0.03, f, 0.22);
            pose(finger_joint(f, 1), z, spread[f] * 0.5);
        }
        pose(W, x, -10);
        pose(W, z, 4);
        pose(F, y, -15);
        pose(F, z, -10);
        pose(finger_joint(0, 1), z, -20);
        pose(finger_joint(0, 2), x, 15);
        pose(finger_joint(0, 3), x, 10);
        break;
    case hand_motion::hand_on_mouse:
        add(finger_joint(1, 1), x, 30, 9, wave::pulse, 0.0, 1, 0.15);
        add(finger_joint(1, 2), x, 45, 6, wave::pulse, 0.01, 1, 0.15);
        pose(finger_joint(1, 3), x, 20);
        add(finger_joint(2, 1), x, 30, 9, wave::pulse, 0.5, 2, 0.15);
        add(finger_joint(2, 2), x, 45, 6, wave::pulse, 0.51, 2, 0.15);
        pose(finger_joint(2, 3), x, 20);
        for (int f = 3; f < 5; ++f) {
            pose(finger_joint(f, 1), x, 40);
            pose(finger_joint(f, 2), x, 50);
            pose(finger_joint(f, 3), x, 25);
        }
        pose(W, x, -25);  // wrist extended over the mouse
        pose(F, y, -30);   // pronated
        add(W, z, 0, 5, wave::sine, 0.0, -1);
        add(F, y, 0, 4, wave::sine, 0.25, -1);
        pose(finger_joint(0, 1), x, 10);
        pose(finger_joint(0, 1), z, -5);
        pose(finger_joint(0, 2), x, 15);
        pose(finger_joint(0, 3), x, 10);
        break;
    case hand_motion::pointing:
        add(finger_joint(1, 1), x, 0, 6, wave::sine, 0.0, 1);
        for (int f = 2; f < 5; ++f) {
            pose(finger_joint(f, 1), x, 75);
            pose(finger_joint(f, 2), x, 95);
            pose(finger_joint(f, 3), x, 55);
        }
        pose(finger_joint(0, 1), x, 25);
        pose(finger_joint(0, 1), z, -5);
        pose(finger_joint(0, 2), x, 40);
        pose(finger_joint(0, 3), x, 30);
        add(W, x, 0, 18, wave::sine, 0.0, -1);
        add(W, z, 0, 12, wave::sine, 0.25, -1);
        add(F, y, 0, 10, wave::sine, 0.1, -1);
        add(F, x, 25, 8, wave::sine, 0.5, -1);  // arm raised toward the target
        break;
    case hand_motion::pushing:
        add(W, x, -10, -35, wave::raised, 0.0, -1);
        add(F, x, 35, 15, wave::raised, -0.05, -1);  // arm raised forward, swinging with the push
        add(F, 5, 0, 12, wave::raised, 0.0, -1);  // root translation along +Z (toward the palm), cm
        for (int f = 1; f < 5; ++f) {
            add(finger_joint(f, 1), x, 0, -8, wave::raised, 0.03, f);
            pose(finger_joint(f, 1), z, spread[f] * 1.2);
        }
        pose(finger_joint(0, 1), z, -25);
        pose(finger_joint(0, 1), x, -5);
        break;
    case hand_motion::waving:
        pose(F, x, 60);  // forearm raised
        add(W, z, 0, 25, wave::sine, 0.0, -1);  // side to side
        add(F, y, 0, 10, wave::sine, 0.05, -1);
        for (int f = 1; f < 5; ++f) {
            add(finger_joint(f, 1), x, 5, 6, wave::sine, 0.15 + 0.03 * f, f);  // fingers trailing the wave
            pose(finger_joint(f, 1), z, spread[f] * 1.5);
        }
        pose(finger_joint(0, 1), z, -30);
        break;
    case hand_motion::counting:
        for (int f = 0; f < 5; ++f) {  // from a fist, thumb .. pinky extend one after another, then close
            const double seq = 0.12 * f;
            if (f == 0) {
                add(finger_joint(0, 1), x, 25, -20, wave::plateau, seq, 0);
                add(finger_joint(0, 2), x, 35, -30, wave::plateau, seq + 0.02, 0);
                add(finger_joint(0, 3), x, 30, -25, wave::plateau, seq + 0.03, 0);
                pose(finger_joint(0, 1), z, -10);
                continue;
            }
            add(finger_joint(f, 1), x, 70, -65, wave::plateau, seq, f);
            add(finger_joint(f, 2), x, 90, -85, wave::plateau, seq + 0.02, f);
            add(finger_joint(f, 3), x, 50, -45, wave::plateau, seq + 0.03, f);
            pose(finger_joint(f, 1), z, spread[f]);
        }
        pose(F, y, 20);
        pose(F, x, 30);
        break;
    case hand_motion::scratching:
        for (int f = 1; f < 5; ++f) {  // quick flexion of the four fingers together, the wrist still
            add(finger_joint(f, 1), x, 35, 20, wave::sine, 0.02 * f, f);
            add(finger_joint(f, 2), x, 50, 25, wave::sine, 0.05 + 0.02 * f, f);
            add(finger_joint(f, 3), x, 30, 15, wave::sine, 0.07 + 0.02 * f, f);
        }
        pose(W, x, 20);
        pose(F, y, -40);
        pose(finger_joint(0, 1), z, -15);
        pose(finger_joint(0, 2), x, 20);
        break;
    case hand_motion::piano:
        for (int f = 0; f < 5; ++f) {  // presses thumb .. pinky in sequence on an arched hand
            const double seq = 0.18 * f;
            add(finger_joint(f, 1), x, 25, 25, wave::pulse, seq, f, 0.16);
            add(finger_joint(f, 2), x, 40, 15, wave::pulse, seq + 0.01, f, 0.16);
            pose(finger_joint(f, 3), x, 15);
        }
        pose(W, x, -5);
        pose(F, y, -60);  // pronated over the keys
        add(F, z, 0, 5, wave::sine, 0.0, -1);
        break;
    case hand_motion::beckoning:
        pose(F, y, 70);  // supinated: palm up
        pose(F, x, 30);
        for (int f = 1; f < 3; ++f) {  // index and middle curl in and out
            add(finger_joint(f, 1), x, 10, 55, wave::raised, 0.03 * f, f);
            add(finger_joint(f, 2), x, 10, 70, wave::raised, 0.03 * f + 0.02, f);
            add(finger_joint(f, 3), x, 5, 40, wave::raised, 0.03 * f + 0.04, f);
        }
        for (int f = 3; f < 5; ++f) {
            pose(finger_joint(f, 1), x, 60);
            pose(finger_joint(f, 2), x, 80);
            pose(finger_joint(f, 3), x, 40);
        }
        pose(finger_joint(0, 1), z, -20);
        pose(finger_joint(0, 2), x, 20);
        add(W, x, 0, 8, wave::raised, 0.05, -1);
        break;
    }
    return t;
}

inline std::uint64_t synth_seed(hand_motion m, emotion e, int take, std::uint64_t seed) noexcept
{
    const std::uint64_t key = (static_cast<std::uint64_t>(m) << 40) ^ (static_cast<std::uint64_t>(e) << 32) ^
                              static_cast<std::uint32_t>(take);
    return splitmix64(seed ^ splitmix64(key + 0x68616e64656d6fULL));
}

}  // namespace detail

namespace detail {

/// One take of `motion` with the style `st`, its per-take variation drawn from `rng_seed`. The sequence of
/// random draws does not depend on the style, so one seed gives the same variation under every style
/// (synthesize_as() relies on it).
inline clip synthesize_take(hand_motion motion, const emotion_style& st, std::uint64_t rng_seed, double fps, const char* who)
{
    if (!(fps > 0) || !std::isfinite(fps) || fps > 10000)
        throw value_error(std::string(who) + ": fps " + std::to_string(fps) + " is not in (0, 10000]");
    synth_rng rng(rng_seed);
    const double tempo_var = rng.uniform(0.93, 1.07);
    const double amp_var = rng.uniform(0.9, 1.1);
    const double phase0 = rng.uniform(-0.03, 0.03);
    const double lag_sign = rng.uniform() < 0.5 ? -1.0 : 1.0;
    std::array<double, 5> finger_lag{}, tremor_hz{}, tremor_phase{};
    for (std::size_t f = 0; f < 5; ++f) {
        finger_lag[f] = st.phase_lag * (lag_sign * static_cast<double>(f) + 0.25 * rng.normal());
        tremor_hz[f] = st.tremor_hz * rng.uniform(0.9, 1.1);
        tremor_phase[f] = rng.uniform();
    }
    auto tracks = motion_tracks(motion);
    std::vector<double> amp_jit(tracks.size()), base_jit(tracks.size());
    for (std::size_t i = 0; i < tracks.size(); ++i) {
        amp_jit[i] = rng.uniform(0.95, 1.05);
        base_jit[i] = tracks[i].axis < 3 ? 2.0 * rng.normal() : 0.0;
    }

    const skeleton skel = hand_skeleton();
    const std::size_t J = skel.size();
    // Smooth noise: three sinusoids per rotation channel.
    struct sinusoid {
        double a, hz, ph;
    };
    std::vector<std::array<sinusoid, 3>> noise(J * 3);
    for (auto& ch : noise)
        for (auto& s : ch) s = {st.noise_deg / std::sqrt(3.0) * rng.normal(), rng.uniform(0.3, 1.5), rng.uniform()};

    const double period = neutral_period(motion) * tempo_var / st.tempo;
    const double duration = synth_cycles * period;
    const auto n = static_cast<std::size_t>(std::max(2.0, std::round(duration * fps))) + 1;
    clip c = clip::make(skel, n, fps);
    constexpr double tau = 2.0 * std::numbers::pi;
    std::vector<double> v(J * 6);
    for (std::size_t f = 0; f < n; ++f) {
        const double phi = synth_cycles * static_cast<double>(f) / static_cast<double>(n - 1);  // cycles
        const double t = static_cast<double>(f) / fps;
        std::fill(v.begin(), v.end(), 0.0);
        for (std::size_t i = 0; i < tracks.size(); ++i) {
            const auto& tr = tracks[i];
            double ph = phi + phase0 - tr.phase;
            if (tr.finger >= 0) ph -= finger_lag[static_cast<std::size_t>(tr.finger)];
            double w = tr.amp != 0.0 ? shape(wave_value(tr.w, ph, tr.width), st.sharpness) : 0.0;
            const double amp = tr.amp * amp_var * amp_jit[i] * st.amplitude;
            const double off = tr.axis < 3 ? tr.base + base_jit[i] : tr.base;
            v[tr.joint * 6 + tr.axis] += off + amp * w;
        }
        // Posture (droop), bounce and tremor.
        v[hand_index::wrist * 6 + 0] += st.droop_deg + st.bounce_deg * std::sin(tau * 2.0 * (phi + phase0));
        for (std::size_t fi = 0; fi < 5; ++fi) {
            for (std::size_t s = 1; s < 3; ++s) v[hand_index::finger_joint(fi, s) * 6] += 0.5 * st.droop_deg;
            if (st.tremor_deg > 0)
                for (std::size_t s = 1; s < 4; ++s)
                    v[hand_index::finger_joint(fi, s) * 6] +=
                        st.tremor_deg * std::sin(tau * (tremor_hz[fi] * t + tremor_phase[fi] + 0.1 * static_cast<double>(s)));
        }
        if (st.tremor_deg > 0) v[hand_index::wrist * 6] += 0.5 * st.tremor_deg * std::sin(tau * (tremor_hz[0] * t + 0.3));
        for (std::size_t j = 0; j < J; ++j) {
            const joint& jt = skel.joints[j];
            for (std::size_t a = 0; a < 3; ++a) {
                double ang = v[j * 6 + a];
                for (const auto& s : noise[j * 3 + a]) ang += s.a * std::sin(tau * (s.hz * t + s.ph));
                c.angle(f, j, a) = std::clamp(ang, jt.lower_limit[a], jt.upper_limit[a]);
            }
            if (jt.has_position())
                for (std::size_t a = 0; a < 3; ++a) c.position(f, j, a) = jt.offset[a] + v[j * 6 + 3 + a];
        }
    }
    return c;
}

}  // namespace detail

/// @brief Synthesises one take: `motion` performed with `emo`, exactly 2 cycles, on hand_skeleton().
/// @param take take number (any int; different takes differ by the seeded per-take variation)
/// @param seed dataset seed; the same (motion, emotion, take, seed, fps) always gives the same clip
/// @param fps frame rate (> 0)
/// @return a clip of round(2 period / tempo x fps) + 1 frames, angles within every joint limit, root
///         translation (pushing only) in the forearm's position channels.
/// @throws value_error for a non-positive fps.
inline clip synthesize(hand_motion motion, emotion emo, int take, std::uint64_t seed, double fps = 60.0)
{
    return detail::synthesize_take(motion, style_of(motion, emo), detail::synth_seed(motion, emo, take, seed), fps, "synthesize");
}

/// @brief The oracle of a transfer on the synthetic set: take `take` of `input_emotion` performed again with
/// `target_emotion`'s style, keeping the input take's per-take variation (tempo, amplitude and per-track
/// jitter, phases, base pose, noise: the same random draws). Its distance to the real take of
/// `target_emotion` is what per-take variation alone leaves: no transfer that sees only the input can be
/// expected to come closer. synthesize_as(m, e, e, ...) == synthesize(m, e, ...).
/// @param take, seed, fps as for synthesize() (those of the input take)
/// @return a clip of round(2 period / tempo x fps) + 1 frames, with the target's tempo and the input's tempo jitter.
/// @throws value_error for a non-positive fps.
inline clip synthesize_as(hand_motion motion, emotion input_emotion, emotion target_emotion, int take, std::uint64_t seed,
                          double fps = 60.0)
{
    return detail::synthesize_take(motion, style_of(motion, target_emotion), detail::synth_seed(motion, input_emotion, take, seed), fps,
                                   "synthesize_as");
}

/// @brief File stem of a take: `hand_<motion>_<emotion>_<take>` (motion names use '-', e.g. hand-on-mouse).
inline std::string file_stem(hand_motion m, emotion e, int take)
{
    return "hand_" + std::string(to_string(m)) + "_" + std::string(to_string(e)) + "_" + std::to_string(take);
}

/// @brief Labels parsed from a file stem `hand_<motion>_<emotion>_<take>`.
struct stem_labels {
    hand_motion motion;
    emotion emo;
    int take;
};

/// @brief Parses `hand_<motion>_<emotion>_<take>`.
/// @throws value_error naming the stem and the part (motion, emotion or take) that is wrong.
inline stem_labels parse_file_stem(std::string_view stem)
{
    std::vector<std::string_view> parts;
    std::size_t start = 0;
    for (std::size_t i = 0; i <= stem.size(); ++i)
        if (i == stem.size() || stem[i] == '_') {
            parts.push_back(stem.substr(start, i - start));
            start = i + 1;
        }
    if (parts.size() != 4 || parts[0] != "hand")
        throw value_error("file name '" + std::string(stem) + "': expected hand_<motion>_<emotion>_<take>");
    stem_labels l{};
    try {
        l.motion = hand_motion_from_string(parts[1]);
        l.emo = emotion_from_string(parts[2]);
    } catch (const value_error& e) {
        throw value_error("file name '" + std::string(stem) + "': " + e.what());
    }
    const std::string_view tk = parts[3];
    if (tk.empty() || tk.size() > 9 || !std::all_of(tk.begin(), tk.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
        throw value_error("file name '" + std::string(stem) + "': take '" + std::string(tk) + "' is not a number");
    l.take = std::stoi(std::string(tk));
    return l;
}

/// @brief One take of the synthetic dataset.
struct synth_item {
    hand_motion motion;
    emotion emo;
    int take;
    clip c;
    std::string file_stem;  ///< hand_<motion>_<emotion>_<take>
};

/// @brief The whole dataset: the set's motions (7 or 12) x 5 emotions x `takes` takes (0 .. takes-1), motion-major
/// order. A take is the same clip in both sets (its seed depends on motion, emotion, take and seed only), so the
/// extended set begins with the paper set.
/// @throws value_error when takes < 1.
inline std::vector<synth_item> synthesize_dataset(int takes, std::uint64_t seed, double fps = 60.0, motion_set set = motion_set::paper)
{
    if (takes < 1) throw value_error("synthesize_dataset: takes " + std::to_string(takes) + " is below 1");
    std::vector<synth_item> out;
    const auto motions = motions_of(set);
    out.reserve(motions.size() * emotion_count * static_cast<std::size_t>(takes));
    for (hand_motion m : motions)
        for (emotion e : all_emotions)
            for (int k = 0; k < takes; ++k) out.push_back({m, e, k, synthesize(m, e, k, seed, fps), file_stem(m, e, k)});
    return out;
}

}  // namespace handemo
