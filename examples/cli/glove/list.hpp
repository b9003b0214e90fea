// `handemo glove list`: the HID devices hidapi sees, with vendor/product ids and usage.
#pragma once

#include "common.hpp"

#include <iostream>

namespace handemo::cli::glove_cmd {

inline void add_list(CLI::App* glove)
{
    auto* sub = glove->add_subcommand("list", "List HID devices (vendor:product, usage page/usage, path, names)");
    sub->callback([] {
        const auto devs = enumerate_hid();
        if (devs.empty()) {
            std::cout << "no HID devices found (is the glove paired/plugged in, and /dev/hidraw* readable by you?)\n";
            return;
        }
        for (const auto& d : devs) {
            char ids[64];
            std::snprintf(ids, sizeof ids, "%04x:%04x  usage %04x:%04x", d.vendor_id, d.product_id, d.usage_page, d.usage);
            std::cout << ids << "  " << d.path << "  " << d.manufacturer << (d.manufacturer.empty() ? "" : " ") << d.product << "\n";
        }
    });
}

}  // namespace handemo::cli::glove_cmd
