// The motion subcommands (synth, encode, decode, info) in one translation unit: every subcommand
// compiles CLI11's inline functions again, so fewer translation units build faster.
#include "registry.hpp"

#include "motion/synth.hpp"
#include "motion/encode.hpp"
#include "motion/decode.hpp"
#include "motion/info.hpp"
#include "motion/retarget.hpp"
