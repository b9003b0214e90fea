// The picture subcommands (render, view, image, plot) in one translation unit (fewer translation units:
// CLI11's inline functions compile once).
#include "registry.hpp"

#include "render/render.hpp"
#include "render/view.hpp"
#include "render/image.hpp"
#include "render/plot.hpp"
