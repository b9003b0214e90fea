// `handemo export --header MODEL --out model.hpp`: writes a trained generator as a C++ header of constexpr
// weights plus its configuration (stargan/export.hpp), for handemo::micro::generator on a microcontroller.
#pragma once

#include "../registry.hpp"

#include <handemo/core/io.hpp>
#include <handemo/stargan/export.hpp>
#include <handemo/stargan/train.hpp>

#include <fstream>
#include <iostream>
#include <memory>
#include <string>

namespace handemo::cli::export_cmd {

struct export_cli {
    std::string model, inference, out;
    stargan::header_export_options opt;
    bool no_self_test = false;
    bool half = false;
};

inline void run_export(export_cli& o)
{
    if (o.model.empty() == o.inference.empty()) throw value_error("export: give one of --header MODEL or --inference MODEL");
    if (!o.inference.empty()) {
        namespace fs = std::filesystem;
        const fs::path in = stargan::checkpoint_file(o.inference);
        const auto slim = stargan::inference_checkpoint(stargan::read_checkpoint(in).first, o.half);
        (void)stargan::parse_checkpoint(slim);  // what load_model() will check
        write_safetensors(o.out, slim);
        std::cout << "export: " << in.string() << " -> " << o.out << " (inference only: metadata and the generator's weights"
                  << (o.half ? " as binary16" : "") << ", "
                  << fs::file_size(o.out) << " bytes)\n";
        return;
    }
    o.opt.self_test = !o.no_self_test;
    const std::string text = stargan::export_generator_header(o.model, o.opt);
    std::ofstream f(o.out, std::ios::binary);
    if (!f) throw io_error("export: cannot write " + o.out);
    f << text;
    f.close();
    if (!f) throw io_error("export: writing " + o.out + " failed");
    std::cout << "export: " << o.model << " -> " << o.out << " (" << text.size() << " bytes of C++)\n";
}

}  // namespace handemo::cli::export_cmd

static handemo::cli::add_command reg_export{55, [](CLI::App& app) {
    auto* sub = app.add_subcommand("export", "Write a trained generator as a C++ header (constexpr weights + config) for handemo::micro");
    auto o = std::make_shared<handemo::cli::export_cmd::export_cli>();
    sub->add_option("--header", o->model, "Model folder or checkpoint.safetensors written by 'handemo train': write a C++ header");
    sub->add_option("--inference", o->inference,
                    "Model folder or checkpoint.safetensors: write its inference part (metadata and generator weights, what "
                    "'transfer --model' reads) as a smaller checkpoint");
    sub->add_option("--out", o->out, "File to write: the header (e.g. model.hpp) or, with --inference, the checkpoint")->required();
    sub->add_flag("--half", o->half, "With --inference: store the weights as IEEE binary16 (half the bytes; the weights rounded)");
    sub->add_option("--namespace", o->opt.name_space, "Namespace of the generated struct")->capture_default_str();
    sub->add_option("--name", o->opt.struct_name, "Name of the generated struct")->capture_default_str();
    sub->add_option("--self-test-emotion", o->opt.self_test_emotion, "Target domain of the embedded self-test (default: the first non-neutral)");
    sub->add_flag("--no-self-test", o->no_self_test, "Do not embed the host-computed self-test input/output");
    sub->callback([o] { handemo::cli::export_cmd::run_export(*o); });
}};
