// Glove module: read a data glove live or from a recording and turn it into clips of the 23-joint hand,
// so a user can capture their own data set and see the emotion transfer on their own hand. Transports
// (serial, TCP, replay, fake; the HID transport is <handemo/glove/hid.hpp>, target handemo::glove, the
// only part that needs hidapi), the reader thread, the protocols (HID profiles as JSON data, Senso JSON
// lines, OpenGloves alpha encoding, the 5DT Data Glove Ultra), calibration and the sensor-to-joint solve,
// the recorder. Needs only the core target.
#pragma once

#include <handemo/glove/detail/quat.hpp>
#include <handemo/glove/profile.hpp>
#include <handemo/glove/transport.hpp>
#include <handemo/glove/serial.hpp>
#include <handemo/glove/tcp.hpp>
#include <handemo/glove/reader.hpp>
#include <handemo/glove/senso.hpp>
#include <handemo/glove/opengloves.hpp>
#include <handemo/glove/fivedt.hpp>
#include <handemo/glove/protocols.hpp>
#include <handemo/glove/solve.hpp>
#include <handemo/glove/recorder.hpp>
