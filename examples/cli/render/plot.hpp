// `handemo plot LOG.csv --out losses.svg`: an SVG of StarGAN training losses (Eq. 4 / Eq. 5 terms, one
// curve per CSV column after `step`, log y axis when the values span more than a decade), or, when the
// CSV header is `metric,method,mean,std`, grouped bars with error bars of an evaluation summary.
#pragma once

#include "../registry.hpp"

#include <handemo/core/io.hpp>
#include <handemo/render/svg.hpp>

#include <iostream>
#include <string>

static handemo::cli::add_command reg_plot{62, [](CLI::App& app) {
    struct args {
        std::string in, out, title;
    };
    auto a = std::make_shared<args>();
    auto* sub = app.add_subcommand("plot", "Plot a training-loss CSV (or a metric,method,mean,std summary) as SVG");
    sub->add_option("input", a->in, "CSV: step,<loss>,... or metric,method,mean,std")->required()->check(CLI::ExistingFile);
    sub->add_option("--out,-o", a->out, "output .svg")->required();
    sub->add_option("--title", a->title, "plot title");
    sub->callback([a] {
        const std::string text = handemo::read_file(a->in);
        std::string svg;
        if (handemo::is_bar_csv(text)) {
            const auto bars = handemo::parse_bar_csv(text, a->in);
            handemo::bar_plot_options o;
            if (!a->title.empty()) o.title = a->title;
            svg = handemo::plot_bars_svg(bars, o);
            std::cout << "wrote " << a->out << " (" << bars.size() << " bars)\n";
        } else {
            const auto log = handemo::parse_loss_csv(text, a->in);  // errors name the input file
            handemo::loss_plot_options o;
            if (!a->title.empty()) o.title = a->title;
            svg = handemo::plot_losses_svg(text, o);
            std::cout << "wrote " << a->out << " (" << log.terms.size() << " loss terms, " << log.steps.size() << " rows)\n";
        }
        handemo::write_file_atomic(a->out, svg);
    });
}};
