// Browser check of the viewer page (render/viewer.hpp) in headless Chromium: a generated page is opened at
// `view.html?t=0.4` with `chromium --headless --dump-dom` (flags for a closed network and a fresh profile),
// and the test requires
//   - nothing on the console: the page's data-status is "ok" (its script hooks window.onerror,
//     unhandledrejection and console.error/console.warn), and Chromium's log (--enable-logging=stderr)
//     has no CONSOLE line from the page, which catches a syntax error no hook can;
//   - the frame drawn for each clip at t = 0.4 s is handemo's (floor(t fps)), and the centre of every joint
//     the page drew (recorded from its drawing calls) equals handemo's forward kinematics projected in C++
//     within 1 px, and the canvas pixel read back at each centre is opaque (ink where a joint was drawn).
// Returns 77 (CTest SKIP_RETURN_CODE) when no Chromium is installed: set HANDEMO_CHROMIUM to a browser binary
// or install Debian's chromium (./setup.sh does). With the arguments `node SCRIPT` it runs the page's script
// under Node with the fake DOM in SCRIPT (viewer_fake_dom.js) instead (77 when there is no node), which
// checks the script and its projection at t = 0 but not the drawing.
#include "helpers.hpp"
#include "viewer_helpers.hpp"

#include <handemo/core/io.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

std::string run(const std::string& cmd)
{
    std::string out;
    if (FILE* p = popen(cmd.c_str(), "r")) {
        char buf[65536];
        std::size_t n;
        while ((n = fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
        pclose(p);
    }
    return out;
}

}  // namespace

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
            std::cout << "SKIP: no Chromium (looked for /usr/bin/chromium, chromium-browser, google-chrome, $HANDEMO_CHROMIUM; "
                         "./setup.sh installs Debian's chromium)\n";
            return 77;
        }
    }
    using namespace handemo;
    const std::vector<clip> clips{test::flexing_hand(30), test::stick_body(20)};
    const double t = node ? 0.0 : 0.4;  // 0.4 s: frame 12 of both 30 fps clips
    std::string html = render_viewer_html(clips);
    // HANDEMO_VIEWER_INJECT=<js>: a script appended to the page, for the test that shows a console error fails
    if (const char* inj = std::getenv("HANDEMO_VIEWER_INJECT"); inj && *inj)
        html.insert(html.rfind("</body>"), std::string("<script>") + inj + "</script>\n");
    const fs::path dir = fs::temp_directory_path() / ("handemo_viewer_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path page = dir / "view.html", log = dir / "chromium.log";
    write_file_atomic(page, html);
    const std::string cmd =
        node ? "'" + browser + "' '" + std::string(argv[2]) + "' '" + page.string() + "' 2>&1"
             : "timeout 25 '" + browser + "' --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
               "--disable-background-networking --disable-component-update --disable-sync --user-data-dir='" +
                   (dir / "profile").string() + "' --enable-logging=stderr --v=0 --virtual-time-budget=2000 --dump-dom 'file://" +
                   page.string() + "?t=0.4' 2>'" + log.string() + "'";
    const auto t0 = std::chrono::steady_clock::now();
    const std::string dom = run(cmd);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::string console;
    if (!node && fs::exists(log)) {
        std::istringstream ls(read_file(log));
        for (std::string l; std::getline(ls, l);)
            if (l.find(":CONSOLE") != std::string::npos) console += "  " + l + "\n";
    }
    fs::remove_all(dir);
    if (!console.empty()) {
        std::cerr << "FAIL: the page wrote to the console:\n" << console;
        return 1;
    }
    const auto at = dom.find("id=\"check\"");
    if (at == std::string::npos) {
        std::cerr << "FAIL: no <pre id=\"check\"> in the dumped DOM (" << dom.size() << " bytes, " << secs << " s)\n" << dom.substr(0, 500) << "\n";
        return 1;
    }
    const auto tag_end = dom.find('>', at);
    const std::string tag = dom.substr(at, tag_end - at);
    if (tag.find("data-status=\"ok\"") == std::string::npos) {
        std::cerr << "FAIL: the page did not finish drawing cleanly: " << tag << " " << dom.substr(tag_end + 1, 300) << "\n";
        return 1;
    }
    const std::string text = dom.substr(tag_end + 1, dom.find("</pre>", tag_end) - tag_end - 1);
    const auto d = test::viewer_data(html);
    std::istringstream lines(text);
    std::string line;
    std::size_t ci = 0, checked = 0;
    double worst = 0;
    bool ink_line = false;
    while (std::getline(lines, line)) {
        if (line.empty()) continue;
        if (line.rfind("ink ", 0) == 0) {
            ink_line = true;
            continue;
        }
        // "clip i frame f: p:x,y ..."
        std::size_t ci_read = 0, f = 0;
        if (std::sscanf(line.c_str(), "clip %zu frame %zu:", &ci_read, &f) != 2 || ci_read != ci || ci >= clips.size()) {
            std::cerr << "FAIL: unexpected check line '" << line.substr(0, 80) << "'\n";
            return 1;
        }
        const std::size_t want_f = std::min(clips[ci].frames - 1, static_cast<std::size_t>(std::floor(t * clips[ci].fps + 1e-9)));
        if (f != want_f) {
            std::cerr << "FAIL: clip " << ci << ": the page drew frame " << f << " at t = " << t << " s, expected " << want_f << "\n";
            return 1;
        }
        const auto expect = test::viewer_expected_pixels(clips[ci], ci, d, f);
        std::size_t visible = 0;
        for (const auto& h : d["clips"][ci]["hidden"]) visible += h.get<int>() ? 0 : 1;
        std::istringstream pts(line.substr(line.find(": ") + 2));
        std::string item;
        std::size_t drawn = 0;
        while (pts >> item) {
            std::size_t p = 0;
            double x = 0, y = 0;
            if (std::sscanf(item.c_str(), "%zu:%lf,%lf", &p, &x, &y) != 3 || p >= expect.size()) {
                std::cerr << "FAIL: clip " << ci << ": bad point '" << item << "' (" << expect.size() << " points)\n";
                return 1;
            }
            worst = std::max({worst, std::abs(x - expect[p][0]), std::abs(y - expect[p][1])});
            ++drawn, ++checked;
        }
        if (drawn != visible) {
            std::cerr << "FAIL: clip " << ci << ": " << drawn << " joints drawn, expected " << visible << "\n";
            return 1;
        }
        ++ci;
    }
    if (ci != clips.size() || !ink_line || worst > 1.0) {
        std::cerr << "FAIL: " << ci << " clips checked of " << clips.size() << (ink_line ? "" : ", no ink line")
                  << ", largest pixel difference " << worst << "\n";
        return 1;
    }
    std::cout << "ok: " << checked << " drawn joints at t = " << t << " s within " << worst << " px of handemo's forward kinematics, "
              << "ink under every one, no console output (" << browser << ", " << secs << " s)\n";
    return 0;
}
