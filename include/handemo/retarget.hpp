// Retargeting module: moves motion between skeletons of different naming, hierarchy, rest pose, channel order,
// units and proportions (world-space bone frames relative to each skeleton's rest pose), picks one hand out of a
// body (mirroring a left hand onto a right-hand model), and writes a result back onto the user's own skeleton
// touching only the driven rotation channels.
#pragma once

#include <handemo/retarget/rotation.hpp>
#include <handemo/retarget/conventions.hpp>
#include <handemo/retarget/map.hpp>
#include <handemo/retarget/map_file.hpp>
#include <handemo/retarget/apply.hpp>
