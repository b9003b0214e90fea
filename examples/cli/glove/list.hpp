// `handemo glove list`: the HID devices hidapi sees (vendor/product ids, usage; a 5DT Data Glove Ultra is
// named), the serial ports that look like a glove (USB serial, USB ACM, Bluetooth RFCOMM, with their
// /dev/serial/by-id names) and the protocols to try on each, and where the Senso server is looked for.
#pragma once

#include "common.hpp"

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <vector>

namespace handemo::cli::glove_cmd {

/// Serial devices under `dev` named like USB serial adapters, USB ACM boards or Bluetooth serial links, with
/// their /dev/serial/by-id names where udev made them.
inline std::vector<std::pair<std::string, std::string>> glove_serial_ports(const std::filesystem::path& dev = "/dev")
{
    namespace fs = std::filesystem;
    std::map<std::string, std::string> by_id;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dev / "serial" / "by-id", ec))
        if (const auto target = fs::canonical(e.path(), ec); !ec) by_id[target.string()] = e.path().filename().string();
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& e : fs::directory_iterator(dev, ec)) {
        const std::string n = e.path().filename().string();
        if (n.starts_with("ttyUSB") || n.starts_with("ttyACM") || n.starts_with("rfcomm")) {
            const auto it = by_id.find(e.path().string());
            out.emplace_back(e.path().string(), it == by_id.end() ? "" : it->second);
        }
    }
    std::sort(out.begin(), out.end());
    return out;
}

inline void add_list(CLI::App* glove)
{
    auto* sub = glove->add_subcommand("list", "List HID devices and serial ports that may be gloves, and the --glove to try on each");
    sub->callback([] {
#ifdef HANDEMO_HAVE_HIDAPI
        const auto devs = enumerate_hid();
        if (devs.empty()) std::cout << "no HID devices found (is the glove paired/plugged in, and /dev/hidraw* readable by you?)\n";
        for (const auto& d : devs) {
            char ids[64];
            std::snprintf(ids, sizeof ids, "%04x:%04x  usage %04x:%04x", d.vendor_id, d.product_id, d.usage_page, d.usage);
            std::cout << ids << "  " << d.path << "  " << d.manufacturer << (d.manufacturer.empty() ? "" : " ") << d.product;
            if (d.vendor_id == fivedt_vendor_id)
                std::cout << "  (5DT Data Glove " << ((d.product_id & 0x10) ? 5 : 14) << " Ultra, " << ((d.product_id & 1) ? "left" : "right")
                          << ": --glove 5dt --sensors " << ((d.product_id & 0x10) ? 5 : 14) << " --hand " << ((d.product_id & 1) ? "left" : "right") << ")";
            std::cout << "\n";
        }
#else
        std::cout << "HID devices: not listed (this handemo was built without hidapi)\n";
#endif
        const auto ports = glove_serial_ports();
        if (ports.empty()) std::cout << "no serial ports that look like a glove (/dev/ttyUSB*, /dev/ttyACM*, /dev/rfcomm*)\n";
        for (const auto& [path, id] : ports)
            std::cout << "serial " << path << (id.empty() ? "" : "  " + id) << "  (try --glove opengloves --device " << path << ")\n";
        std::cout << "senso: its server is looked for at 127.0.0.1:53450 (--glove senso [--device HOST:PORT])\n";
    });
}

}  // namespace handemo::cli::glove_cmd
