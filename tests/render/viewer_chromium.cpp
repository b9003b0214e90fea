// Browser check of the viewer page (render/viewer.hpp) in headless Chromium: generated pages are opened at
// `view.html?t=0.4` with `chromium --headless --dump-dom` (flags for a closed network and a fresh profile),
// and the test requires of each
//   - nothing on the console: the page's data-status is "ok" (its script hooks window.onerror,
//     unhandledrejection and console.error/console.warn), and Chromium's log (--enable-logging=stderr)
//     has no CONSOLE line from the page, which catches a syntax error no hook can;
//   - the frame drawn for each clip at t = 0.4 s is handemo's (floor(t fps)), and the centre of every joint
//     the page drew (recorded from its drawing calls) equals handemo's forward kinematics projected in C++
//     within 1 px and lies inside the clip's grid cell, and the canvas pixel read back at each centre is
//     opaque (ink where a joint was drawn).
// The pages: two clips in one row, and ten clips in 5 columns, where clip 7 must be drawn in row 1, column 2
// (its cell's corners written out here, not taken from the helper that projects the joints); and a page with a V/A
// grid opened at `?va=0.3,-0.2`, which must draw the input and the output of the nearest grid point in the two
// cells (under node, also a click on the dial and an arrow key, which must pick the expected grid point).
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

namespace fs = std::filesystem;
using namespace handemo;

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

struct page {
    std::string name;
    std::vector<clip> clips;
    viewer_options options;
    std::string query;                 ///< appended to ?t=...: "&va=V,A" picks a point on a grid page's dial
    std::vector<std::size_t> shown;    ///< the clip drawn in each cell (empty: clip i in cell i)
    std::string events, pick;          ///< under node: events sent to the dial, and the data-pick they must give
};

/// Opens one page in the browser (or under node) at time t and checks what it drew; "ok: ..." or what failed.
std::string check_page(const page& pg, const std::string& browser, bool node, const std::string& script, double t)
{
    const std::vector<clip>& clips = pg.clips;
    std::string html = render_viewer_html(clips, pg.options);
    // HANDEMO_VIEWER_INJECT=<js>: a script appended to the page, for the test that shows a console error fails
    if (const char* inj = std::getenv("HANDEMO_VIEWER_INJECT"); inj && *inj)
        html.insert(html.rfind("</body>"), std::string("<script>") + inj + "</script>\n");
    const fs::path dir = fs::temp_directory_path() / ("handemo_viewer_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path file = dir / "view.html", log = dir / "chromium.log";
    write_file_atomic(file, html);
    const std::string cmd =
        node ? "'" + browser + "' '" + script + "' '" + file.string() + "' '?t=0" + pg.query + "' '" + pg.events + "' 2>&1"
             : "timeout 25 '" + browser + "' --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
               "--disable-background-networking --disable-component-update --disable-sync --user-data-dir='" +
                   (dir / "profile").string() + "' --enable-logging=stderr --v=0 --virtual-time-budget=2000 --dump-dom 'file://" +
                   file.string() + "?t=" + std::to_string(t) + pg.query + "' 2>'" + log.string() + "'";
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
    if (!console.empty()) return "the page wrote to the console:\n" + console;
    const auto at = dom.find("id=\"check\"");
    if (at == std::string::npos)
        return "no <pre id=\"check\"> in the dumped DOM (" + std::to_string(dom.size()) + " bytes, " + std::to_string(secs) + " s)\n" +
               dom.substr(0, 500);
    const auto tag_end = dom.find('>', at);
    const std::string tag = dom.substr(at, tag_end - at);
    if (tag.find("data-status=\"ok\"") == std::string::npos)
        return "the page did not finish drawing cleanly: " + tag + " " + dom.substr(tag_end + 1, 300);
    if (!pg.pick.empty() && tag.find("data-pick=\"" + pg.pick) == std::string::npos)
        return "the dial picked another grid point: " + tag + " (expected data-pick \"" + pg.pick + "...\")";
    const std::string text = dom.substr(tag_end + 1, dom.find("</pre>", tag_end) - tag_end - 1);
    const std::size_t cells = pg.shown.empty() ? clips.size() : pg.shown.size();
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
        // cell ci shows clip cl
        std::size_t ci_read = 0, f = 0;
        const std::size_t cl = ci < cells && !pg.shown.empty() ? pg.shown[ci] : ci;
        if (std::sscanf(line.c_str(), "clip %zu frame %zu:", &ci_read, &f) != 2 || ci_read != cl || ci >= cells)
            return "unexpected check line '" + line.substr(0, 80) + "' (expected clip " + std::to_string(cl) + ")";
        const std::size_t want_f = std::min(clips[cl].frames - 1, static_cast<std::size_t>(std::floor(t * clips[cl].fps + 1e-9)));
        if (f != want_f)
            return "clip " + std::to_string(ci) + ": the page drew frame " + std::to_string(f) + " at t = " + std::to_string(t) +
                   " s, expected " + std::to_string(want_f);
        const auto expect = test::viewer_expected_pixels(clips[cl], cl, d, f, ci);
        const test::viewer_cell cell = test::viewer_cell_of(d, ci);
        std::size_t visible = 0;
        for (const auto& h : d["clips"][cl]["hidden"]) visible += h.get<int>() ? 0 : 1;
        std::istringstream pts(line.substr(line.find(": ") + 2));
        std::string item;
        std::size_t drawn = 0;
        while (pts >> item) {
            std::size_t p = 0;
            double x = 0, y = 0;
            if (std::sscanf(item.c_str(), "%zu:%lf,%lf", &p, &x, &y) != 3 || p >= expect.size())
                return "clip " + std::to_string(ci) + ": bad point '" + item + "' (" + std::to_string(expect.size()) + " points)";
            if (x < cell.x || x > cell.x + cell.w || y < cell.y || y > cell.y + cell.h)
                return "clip " + std::to_string(ci) + ": point " + std::to_string(p) + " drawn at (" + std::to_string(x) + ", " +
                       std::to_string(y) + "), outside its cell (row " + std::to_string(cell.row) + ", column " + std::to_string(cell.column) + ")";
            // the grid page's clip 7: row 1, column 2 of 200 x 300 cells under 24-pixel title bands
            if (pg.options.columns == 5 && ci == 7 && !(x >= 400 && x <= 600 && y >= 2 * 24 + 300 && y <= 2 * (24 + 300)))
                return "clip 7: point " + std::to_string(p) + " drawn at (" + std::to_string(x) + ", " + std::to_string(y) +
                       "), not in row 1, column 2 ([400, 600] x [348, 648])";
            worst = std::max({worst, std::abs(x - expect[p][0]), std::abs(y - expect[p][1])});
            ++drawn, ++checked;
        }
        if (drawn != visible)
            return "clip " + std::to_string(ci) + ": " + std::to_string(drawn) + " joints drawn, expected " + std::to_string(visible);
        ++ci;
    }
    if (ci != cells || !ink_line || worst > 1.0)
        return std::to_string(ci) + " clips checked of " + std::to_string(cells) + (ink_line ? "" : ", no ink line") +
               ", largest pixel difference " + std::to_string(worst);
    std::ostringstream ok;
    ok << "ok: " << checked << " drawn joints of " << cells << " clips at t = " << t << " s within " << worst
       << " px of handemo's forward kinematics, each in its cell, ink under every one, no console output (" << secs << " s)";
    return ok.str();
}

}  // namespace

int main(int argc, char** argv)
{
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
    // a single row (two clips, automatic columns), and a grid: ten clips in 5 columns of 200 x 300 pixel cells
    std::vector<clip> grid;
    for (std::size_t i = 0; i < 10; ++i) grid.push_back(i % 2 ? test::stick_body(20) : test::flexing_hand(30));
    viewer_options go;
    go.columns = 5;
    go.width = 1000;
    go.height = 300;
    // a V/A grid page: the input, then the outputs at va_grid(5)'s 13 points (stand-ins of distinct frame counts);
    // ?va=0.3,-0.2 must play the output at the nearest grid point, (0.5, 0): clip 1 + 7. Under node, a click on the
    // dial where (0.3, 0.1) lies (viewer_dial_size, viewer_dial_radius) then an arrow up (0.5) must pick (0.3, 0.6),
    // whose nearest grid point is (0.5, 0.5), index 11.
    const auto points = va_grid(5);
    std::vector<clip> va{test::stick_body(20)};
    for (std::size_t k = 0; k < points.size(); ++k) va.push_back(test::flexing_hand(20 + k));
    viewer_options vo;
    vo.va_grid = viewer_va_grid{1, 5, points, {{"neutral", 0.1, -0.1}, {"happy", 0.8, 0.5}}};
    const std::size_t want = nearest_va_point(points, 0.3, -0.2);
    page vpage{"V/A grid", va, vo, "&va=0.3,-0.2", {0, 1 + want}, "", ""};
    if (node) {
        const double r = viewer_dial_radius * viewer_dial_size, c = viewer_dial_size / 2;
        const auto px = [&](double v, double a) { return std::to_string(c + v * r) + "," + std::to_string(c - a * r); };
        vpage.events = "mousedown:" + px(0.3, 0.1) + ";keydown:ArrowUp";
        vpage.pick = std::to_string(nearest_va_point(points, 0.3, 0.6)) + " 0.3000 0.6000";
    }
    const page pages[] = {{"one row", {test::flexing_hand(30), test::stick_body(20)}, {}, "", {}, "", ""}, {"grid", grid, go, "", {}, "", ""}, vpage};
    const double t = node ? 0.0 : 0.4;  // 0.4 s: frame 12 of the 30 fps clips
    std::string report;
    for (const page& pg : pages) {
        const std::string r = check_page(pg, browser, node, node ? argv[2] : "", t);
        if (r.rfind("ok", 0) != 0) {
            std::cerr << "FAIL: " << pg.name << " page: " << r << "\n";
            return 1;
        }
        report += "  " + pg.name + " page: " + r + "\n";
    }
    std::cout << "ok (" << browser << ")\n" << report;
    return 0;
}
