// Browser check of the viewer page (render/viewer.hpp): loads a generated page with
// `chromium --headless --dump-dom`, requires the page's <pre id="check"> to say data-status="ok" and the
// frame-0 pixel positions it wrote to match handemo's forward kinematics projected in C++ within 1 px.
// Returns 77 (CTest SKIP_RETURN_CODE) when no Chromium is installed: set HANDEMO_CHROMIUM to a browser binary
// or install /usr/bin/chromium. With the arguments `node SCRIPT` it runs the page's script under Node with
// the fake DOM in SCRIPT (viewer_fake_dom.js) instead (77 when there is no node), which checks the script and
// its projection but not the drawing.
#include "helpers.hpp"
#include "viewer_helpers.hpp"

#include <handemo/core/io.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

int main(int argc, char** argv)
{
    namespace fs = std::filesystem;
    const bool node = argc == 3 && std::string(argv[1]) == "node";
    std::string browser;
    if (node) {
        for (const char* c : {"/usr/bin/node", "/usr/bin/nodejs", "/usr/local/bin/node"})
            if (browser.empty() && fs::exists(c)) browser = c;
        if (browser.empty()) {
            std::cout << "SKIP: no node (looked for /usr/bin/node, /usr/bin/nodejs, /usr/local/bin/node)\n";
            return 77;
        }
    } else {
        if (const char* e = std::getenv("HANDEMO_CHROMIUM"); e && *e) browser = e;
        for (const char* c : {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"})
            if (browser.empty() && fs::exists(c)) browser = c;
        if (browser.empty()) {
            std::cout << "SKIP: no Chromium (looked for /usr/bin/chromium, chromium-browser, google-chrome, $HANDEMO_CHROMIUM)\n";
            return 77;
        }
    }
    using namespace handemo;
    const std::vector<clip> clips{test::flexing_hand(30), test::stick_body(20)};
    const std::string html = render_viewer_html(clips);
    const fs::path dir = fs::temp_directory_path() / ("handemo_viewer_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path page = dir / "view.html";
    write_file_atomic(page, html);
    const std::string cmd = node ? "'" + browser + "' '" + std::string(argv[2]) + "' '" + page.string() + "' 2>&1"
                                 : "'" + browser + "' --headless --no-sandbox --disable-gpu --user-data-dir='" + (dir / "profile").string() +
                            "' --virtual-time-budget=2000 --dump-dom 'file://" + page.string() + "' 2>/dev/null";
    std::string dom;
    if (FILE* p = popen(cmd.c_str(), "r")) {
        char buf[65536];
        std::size_t n;
        while ((n = fread(buf, 1, sizeof buf, p)) > 0) dom.append(buf, n);
        pclose(p);
    }
    fs::remove_all(dir);
    const auto at = dom.find("id=\"check\"");
    if (at == std::string::npos) {
        std::cerr << "FAIL: no <pre id=\"check\"> in the dumped DOM (" << dom.size() << " bytes)\n";
        return 1;
    }
    const auto tag_end = dom.find('>', at);
    const std::string tag = dom.substr(at, tag_end - at);
    if (tag.find("data-status=\"ok\"") == std::string::npos) {
        std::cerr << "FAIL: the page did not finish drawing: " << tag << " " << dom.substr(tag_end + 1, 300) << "\n";
        return 1;
    }
    const std::string text = dom.substr(tag_end + 1, dom.find("</pre>", tag_end) - tag_end - 1);
    const auto d = test::viewer_data(html);
    std::istringstream lines(text);
    std::string line;
    std::size_t ci = 0, checked = 0;
    double worst = 0;
    while (std::getline(lines, line)) {
        if (line.empty()) continue;
        const auto colon = line.find(": ");
        std::istringstream pts(line.substr(colon + 2));
        const auto expect = test::viewer_expected_pixels(clips[ci], ci, d);
        std::string xy;
        std::size_t p = 0;
        while (pts >> xy) {
            const auto comma = xy.find(',');
            const double x = std::stod(xy.substr(0, comma)), y = std::stod(xy.substr(comma + 1));
            if (p >= expect.size()) {
                std::cerr << "FAIL: clip " << ci << ": more points than expected (" << expect.size() << ")\n";
                return 1;
            }
            worst = std::max({worst, std::abs(x - expect[p][0]), std::abs(y - expect[p][1])});
            ++p, ++checked;
        }
        if (p != expect.size()) {
            std::cerr << "FAIL: clip " << ci << ": " << p << " points drawn, expected " << expect.size() << "\n";
            return 1;
        }
        ++ci;
    }
    if (ci != clips.size() || worst > 1.0) {
        std::cerr << "FAIL: " << ci << " clips checked of " << clips.size() << ", largest pixel difference " << worst << "\n";
        return 1;
    }
    std::cout << "ok: " << checked << " projected points within " << worst << " px of handemo's forward kinematics\n";
    return 0;
}
