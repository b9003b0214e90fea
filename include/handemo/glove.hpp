// Glove module (target handemo::glove, the only part of handemo that links hidapi): read a data glove
// live or from a recording and turn it into clips of the 23-joint hand, so a user can capture their own
// data set and see the emotion transfer on their own hand. Transports (HID, replay, fake), device
// profiles as JSON data, the report decoder, calibration and the sensor-to-joint solve, the recorder.
#pragma once

#include <handemo/glove/detail/quat.hpp>
#include <handemo/glove/profile.hpp>
#include <handemo/glove/transport.hpp>
#include <handemo/glove/hid.hpp>
#include <handemo/glove/solve.hpp>
#include <handemo/glove/recorder.hpp>
