// Tests of the SVG plots (render/svg.hpp): well-formed XML (checked by a small parser below), one panel per
// group of loss terms, a legend entry for every series, the moving average on a hand-made log, per-fold
// panels, the y-scale decision, escaping, and the CSV errors.
#include <handemo/render/svg.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace handemo;

namespace {

/// Minimal XML well-formedness check: balanced, properly nested tags; attribute values quoted; no raw
/// '<' in text or attributes; every '&' starts one of the five predefined entities. Returns "" when the
/// document is well formed, else a description of the first problem.
std::string xml_problem(const std::string& s)
{
    std::vector<std::string> stack;
    auto entity_ok = [&](std::size_t i) {
        for (const char* e : {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"})
            if (s.compare(i, std::char_traits<char>::length(e), e) == 0) return true;
        return false;
    };
    std::size_t i = 0;
    int roots = 0;
    while (i < s.size()) {
        if (s[i] == '&' && !entity_ok(i)) return "bad entity at " + std::to_string(i);
        if (s[i] != '<') {
            if (s[i] == '>') return "raw '>' in text at " + std::to_string(i);
            ++i;
            continue;
        }
        if (s.compare(i, 5, "<?xml") == 0) {
            const auto e = s.find("?>", i);
            if (e == std::string::npos) return "unterminated declaration";
            i = e + 2;
            continue;
        }
        const bool closing = i + 1 < s.size() && s[i + 1] == '/';
        std::size_t j = i + (closing ? 2 : 1);
        std::string name;
        while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '-' || s[j] == ':')) name += s[j++];
        if (name.empty()) return "tag without a name at " + std::to_string(i);
        // attributes: name="value" pairs
        while (j < s.size() && s[j] != '>' && !(s[j] == '/' && j + 1 < s.size() && s[j + 1] == '>')) {
            if (std::isspace(static_cast<unsigned char>(s[j]))) {
                ++j;
                continue;
            }
            while (j < s.size() && s[j] != '=' && s[j] != '>' && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
            if (j >= s.size() || s[j] != '=' || j + 1 >= s.size() || s[j + 1] != '"') return "unquoted attribute in <" + name + ">";
            j += 2;
            while (j < s.size() && s[j] != '"') {
                if (s[j] == '<') return "'<' in an attribute of <" + name + ">";
                if (s[j] == '&' && !entity_ok(j)) return "bad entity in an attribute of <" + name + ">";
                ++j;
            }
            if (j >= s.size()) return "unterminated attribute in <" + name + ">";
            ++j;
        }
        if (j >= s.size()) return "unterminated tag <" + name + ">";
        const bool self = s[j] == '/';
        i = j + (self ? 2 : 1);
        if (closing) {
            if (stack.empty() || stack.back() != name) return "</" + name + "> does not close <" + (stack.empty() ? "" : stack.back()) + ">";
            stack.pop_back();
        } else if (!self) {
            if (stack.empty()) ++roots;
            stack.push_back(name);
        } else if (stack.empty()) {
            ++roots;
        }
    }
    if (!stack.empty()) return "<" + stack.back() + "> is never closed";
    if (roots != 1) return std::to_string(roots) + " root elements";
    return "";
}

std::size_t count(const std::string& s, const std::string& what)
{
    std::size_t n = 0;
    for (auto p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
    return n;
}

/// Values of an attribute `name="..."` in every element of `s` that contains `marker` in its opening tag.
std::vector<std::string> attr_values(const std::string& s, const std::string& marker, const std::string& name)
{
    std::vector<std::string> out;
    for (auto p = s.find(marker); p != std::string::npos; p = s.find(marker, p + 1)) {
        const auto open = s.rfind('<', p), close = s.find('>', p);
        const std::string tag = s.substr(open, close - open);
        const auto a = tag.find(" " + name + "=\"");
        if (a == std::string::npos) continue;
        const auto b = a + name.size() + 3;
        out.push_back(tag.substr(b, tag.find('"', b) - b));
    }
    return out;
}

/// Text content of every <text class="legend"> element.
std::vector<std::string> legend_names(const std::string& s)
{
    std::vector<std::string> out;
    for (auto p = s.find("class=\"legend\""); p != std::string::npos; p = s.find("class=\"legend\"", p + 1)) {
        const auto b = s.find('>', p) + 1;
        out.push_back(s.substr(b, s.find('<', b) - b));
    }
    return out;
}

/// The full loss log of the trainer: step,D/real,D/fake,D/cls,D/gp,D/total,D/acc,G/fake,G/cls,G/rec,G/total,lr,G/id,G/pair,G/delta.
std::string trainer_log(int rows, bool old_log)
{
    std::string csv = "step,D/real,D/fake,D/cls,D/gp,D/total,D/acc,G/fake,G/cls,G/rec,G/total,lr,G/id,G/pair,G/delta\n";
    for (int s = 0; s < rows; ++s) {
        const double d = 1.0 / (1 + s);
        csv += std::to_string(s * 10) + "," + std::to_string(-1 - d) + "," + std::to_string(1 + (s % 2 ? 1e-8 : -1e-8)) + "," +
               std::to_string(0.7 * d) + "," + std::to_string(10 * d) + "," + std::to_string(2 * d) + "," + std::to_string(0.5 + 0.4 * (1 - d)) +
               "," + std::to_string(-0.5) + "," + std::to_string(0.6 * d) + "," + std::to_string(0.2 + d) + "," + std::to_string(1.1) + "," +
               "0.0001," + (old_log ? "0,nan," : "0.1,0.2,") + (old_log ? "0" : "0.05") + "\n";
    }
    return csv;
}

}  // namespace

TEST_CASE("svg: loss plot is small multiples, one panel per group, every series in the legend")
{
    const std::string svg = plot_losses_svg(trainer_log(300, false));
    CHECK(xml_problem(svg) == "");
    const auto groups = attr_values(svg, "class=\"panel\"", "data-group");
    REQUIRE(groups == std::vector<std::string>{"D terms", "G terms", "D accuracy", "learning rate"});
    const auto series = attr_values(svg, "class=\"ema\"", "data-series");
    CHECK(series.size() == 14);
    CHECK(count(svg, "class=\"raw\"") == 14);
    const auto legend = legend_names(svg);
    CHECK(legend == series);  // one legend entry per drawn series, none without
    CHECK(svg.find("exponential moving average") != std::string::npos);
    CHECK(svg.find("not plotted") == std::string::npos);
    CHECK(svg.find("log scale") == std::string::npos);  // linear axes only
    // colours are distinct within a panel: G terms has 7 series
    std::vector<std::string> strokes = attr_values(svg, "class=\"ema\"", "stroke");
    const std::vector<std::string> g_strokes(strokes.begin() + 5, strokes.begin() + 12);
    for (std::size_t i = 0; i < g_strokes.size(); ++i)
        for (std::size_t j = i + 1; j < g_strokes.size(); ++j) CHECK(g_strokes[i] != g_strokes[j]);

    // an old log: G/id, G/pair, G/delta all 0 or NaN are left out and named in a note
    const std::string old = plot_losses_svg(trainer_log(40, true));
    CHECK(xml_problem(old) == "");
    CHECK(attr_values(old, "class=\"ema\"", "data-series").size() == 11);
    CHECK(legend_names(old).size() == 11);
    CHECK(old.find("not plotted (every value 0 or missing): G/id, G/pair, G/delta") != std::string::npos);

    // names are escaped; d_/g_ prefixes group too
    const std::string esc = plot_losses_svg("step,d_adv,g_rec <L1> & \"more\"\n0,1,2\n1,2,3\n");
    CHECK(xml_problem(esc) == "");
    CHECK(esc.find("g_rec &lt;L1&gt; &amp; &quot;more&quot;") != std::string::npos);
    CHECK(attr_values(esc, "class=\"panel\"", "data-group").size() == 2);
}

TEST_CASE("svg: loss groups and the moving average")
{
    CHECK(loss_group_of("D/real") == "D terms");
    CHECK(loss_group_of("D/acc") == "D accuracy");
    CHECK(loss_group_of("G/delta") == "G terms");
    CHECK(loss_group_of("lr") == "learning rate");
    CHECK(loss_group_of("rec") == "other terms");
    const std::vector<double> x{4, 2, std::nan(""), 6, 0};
    const auto e = exponential_moving_average(x, 0.5);
    CHECK(e[0] == 4);
    CHECK(e[1] == 3);  // 0.5 * 2 + 0.5 * 4
    CHECK(std::isnan(e[2]));
    CHECK(e[3] == 4.5);  // 0.5 * 6 + 0.5 * 3: the NaN row leaves the average
    CHECK(e[4] == 2.25);
    CHECK(loss_ema_alpha(100, 0.3) == 0.3);
    CHECK(loss_ema_alpha(10) == 1.0);         // span 1: no smoothing on a short log
    CHECK(loss_ema_alpha(500) == 2.0 / 21.0);  // span 20
}

TEST_CASE("svg: the drawn average is the stated moving average of a hand-made log")
{
    // hand-made log: x = 0, 10, 0, 10, 0 at steps 0..40, alpha 0.5 -> e = 0, 5, 2.5, 6.25, 3.125
    loss_plot_options o;
    o.ema_alpha = 0.5;
    const std::string svg = plot_losses_svg("step,G/rec\n0,0\n10,10\n20,0\n30,10\n40,0\n", o);
    CHECK(xml_problem(svg) == "");
    CHECK(svg.find("e = 0.5 x + 0.5 e(previous row)") != std::string::npos);
    const auto pts = attr_values(svg, "class=\"ema\"", "points");
    REQUIRE(pts.size() == 1);
    const double lo = std::stod(attr_values(svg, "class=\"panel\"", "data-lo")[0]), hi = std::stod(attr_values(svg, "class=\"panel\"", "data-hi")[0]);
    const double top = std::stod(attr_values(svg, "class=\"panel\"", "y")[0]);
    const double bottom = top + std::stod(attr_values(svg, "class=\"panel\"", "height")[0]);
    std::vector<double> ys;
    std::string p = pts[0];
    for (std::size_t i = 0; i < p.size();) {
        const auto comma = p.find(',', i), space = p.find(' ', comma);
        ys.push_back(std::stod(p.substr(comma + 1, space - comma - 1)));
        if (space == std::string::npos) break;
        i = space + 1;
    }
    const std::vector<double> expect{0, 5, 2.5, 6.25, 3.125};
    REQUIRE(ys.size() == expect.size());
    for (std::size_t i = 0; i < ys.size(); ++i) {
        const double v = lo + (bottom - ys[i]) / (bottom - top) * (hi - lo);
        CHECK(v == doctest::Approx(expect[i]).epsilon(0.002 * (hi - lo)));
    }
    // the raw values are drawn too, faint
    CHECK(count(svg, "stroke-opacity=\"0.28\"") == 1);
}

TEST_CASE("svg: per-fold small multiples")
{
    const std::vector<fold_point> pts{{"RMSE <deg>", "stargan", "crawling", 3.0}, {"RMSE <deg>", "identity", "crawling", 4.0},
                                      {"RMSE <deg>", "stargan", "gripping", 2.0}, {"RMSE <deg>", "identity", "gripping", 5.0},
                                      {"accuracy", "stargan", "crawling", 0.8},   {"accuracy", "identity", "gripping", std::nan("")}};
    const std::string svg = plot_folds_svg(pts);
    CHECK(xml_problem(svg) == "");
    CHECK(svg.find("RMSE &lt;deg&gt;") != std::string::npos);
    CHECK(legend_names(svg) == std::vector<std::string>{"stargan", "identity"});
    CHECK(count(svg, "class=\"series\"") == 3);  // accuracy/identity has no finite value
    CHECK_THROWS_AS(plot_folds_svg({}), value_error);
}

TEST_CASE("svg: track plot: panels, a legend entry per series, a break at each non-finite value")
{
    std::vector<track_series> c{{"sad <wrist>", "real", {0, 0.5, 1}, {1, 2, 3}},
                                {"sad <wrist>", "stargan", {0, 0.5, 1}, {1, std::nan(""), 3}},
                                {"angry", "real", {0, 1}, {-5, 5}}};
    const std::string svg = plot_tracks_svg(c);
    CHECK(xml_problem(svg) == "");
    CHECK(svg.find("sad &lt;wrist&gt;") != std::string::npos);
    CHECK(legend_names(svg) == std::vector<std::string>{"real", "stargan"});
    CHECK(count(svg, "class=\"series\"") == 4);  // the NaN splits stargan's curve in two
    CHECK_THROWS_AS(plot_tracks_svg({}), value_error);
    c[0].t.push_back(0.7);
    CHECK_THROWS_WITH_AS(plot_tracks_svg(c), doctest::Contains("3 values"), value_error);
    c[0].v.push_back(1.0);
    c[0].t.back() = 1.5;
    CHECK_THROWS_WITH_AS(plot_tracks_svg(c), doctest::Contains("outside [0, 1]"), value_error);
}

TEST_CASE("svg: the checker itself rejects broken XML")
{
    CHECK(xml_problem("<svg><g></g></svg>").empty());
    CHECK_FALSE(xml_problem("<svg><g></svg>").empty());
    CHECK_FALSE(xml_problem("<svg>a < b</svg>").empty());
    CHECK_FALSE(xml_problem("<svg>a & b</svg>").empty());
    CHECK_FALSE(xml_problem("<svg x=1></svg>").empty());
    CHECK_FALSE(xml_problem("<svg></svg><svg></svg>").empty());
}

TEST_CASE("svg: y-scale decision")
{
    const std::vector<double> decades{0.01, 0.5, 3.0};      // positive, > 1 decade
    const std::vector<double> narrow{2.0, 3.0, 19.0};       // positive, < 1 decade
    const std::vector<double> mixed{-1.0, 0.5, 2.0};         // both signs, small range
    const std::vector<double> wgan{-40.0, 0.001, 5.0, 0.02}; // both signs, > 3 decades
    const std::vector<double> with_zero{0.0, 0.5, 100.0};    // not all positive
    CHECK(choose_y_scale(decades) == axis_scale::log);
    CHECK(choose_y_scale(narrow) == axis_scale::linear);
    CHECK(choose_y_scale(mixed) == axis_scale::linear);
    CHECK(choose_y_scale(wgan) == axis_scale::symlog);
    CHECK(choose_y_scale(with_zero) == axis_scale::linear);
    CHECK(choose_y_scale({}) == axis_scale::linear);
    const std::vector<double> nan_ignored{std::nan(""), 1.0, 100.0};
    CHECK(choose_y_scale(nan_ignored) == axis_scale::log);
}

TEST_CASE("svg: loss CSV errors name the line and column")
{
    CHECK_THROWS_WITH_AS(plot_losses_svg(""), doctest::Contains("empty"), format_error);
    CHECK_THROWS_WITH_AS(plot_losses_svg("epoch,a\n1,2\n"), doctest::Contains("first column 'epoch' is not 'step'"), format_error);
    CHECK_THROWS_WITH_AS(plot_losses_svg("step\n1\n"), doctest::Contains("no loss column"), format_error);
    CHECK_THROWS_WITH_AS(plot_losses_svg("step,a\n"), doctest::Contains("no data rows"), format_error);
    CHECK_THROWS_WITH_AS(plot_losses_svg("step,a,b\n0,1,2\n1,2\n"), doctest::Contains("line 3: 2 fields, expected 3"), format_error);
    CHECK_THROWS_WITH_AS(plot_losses_svg("step,a,b\n0,1,2\n1,2,x7\n"), doctest::Contains("line 3: column 'b' value 'x7' is not a number"),
                         format_error);
}

TEST_CASE("svg: grouped bars with error bars")
{
    const std::string csv = "metric,method,mean,std\naccuracy,stargan,0.81,0.05\naccuracy,baseline,0.55,0.1\n"
                            "fid <lower>,stargan,12.5,1.5\nfid <lower>,baseline,30,\n";
    CHECK(is_bar_csv(csv));
    CHECK_FALSE(is_bar_csv("step,a\n0,1\n"));
    const auto bars = parse_bar_csv(csv);
    REQUIRE(bars.size() == 4);
    CHECK(bars[3].std == 0);
    const std::string svg = plot_bars_svg(bars);
    CHECK(xml_problem(svg) == "");
    CHECK(count(svg, "<rect") == 1 + 2 + 4);  // background, 2 legend swatches, 4 bars
    CHECK(count(svg, "<line") >= 3 * 3);      // 3 error bars with caps (zero std: none)
    CHECK(svg.find("fid &lt;lower&gt;") != std::string::npos);

    CHECK_THROWS_WITH_AS(parse_bar_csv("metric,method,mean\n"), doctest::Contains("is not 'metric,method,mean,std'"), format_error);
    CHECK_THROWS_WITH_AS(parse_bar_csv("metric,method,mean,std\na,b,1,-2\n"), doctest::Contains("line 2: std -2"), format_error);
    CHECK_THROWS_WITH_AS(parse_bar_csv("metric,method,mean,std\na,b,,1\n"), doctest::Contains("line 2: mean"), format_error);
    CHECK_THROWS_AS(plot_bars_svg({}), value_error);
}
