// Tests of the SVG plots (render/svg.hpp): well-formed XML (checked by a small parser below), one polyline
// per loss term, the y-scale decision, escaping, and the CSV errors.
#include <handemo/render/svg.hpp>

#include <doctest/doctest.h>

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

}  // namespace

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

TEST_CASE("svg: loss plot has one polyline per term, is well formed and escapes names")
{
    std::string csv = "step,d_adv,d_cls,g_rec <L1> & \"more\"\n";
    for (int s = 0; s <= 300; s += 10)
        csv += std::to_string(s) + "," + std::to_string(2.0 / (1 + s)) + "," + std::to_string(0.7 + 0.001 * s) + "," +
               (s == 50 ? std::string("") : std::to_string(0.3 + 1.0 / (1 + s))) + "\n";
    const std::string svg = plot_losses_svg(csv);
    CHECK(xml_problem(svg) == "");
    CHECK(count(svg, "<polyline") == 3);
    CHECK(svg.find("g_rec &lt;L1&gt; &amp; &quot;more&quot;") != std::string::npos);
    CHECK(svg.find("log scale") != std::string::npos);  // 2/301 .. 2: more than a decade, all positive

    const std::string lin = plot_losses_svg("step,a\n0,1\n1,2\n2,3\n");
    CHECK(xml_problem(lin) == "");
    CHECK(lin.find("log scale") == std::string::npos);
    const std::string sym = plot_losses_svg("# a comment\nstep,d_adv,gp\r\n0,-40,0.001\r\n1,5,0.02\r\n");
    CHECK(xml_problem(sym) == "");
    CHECK(sym.find("symmetric log scale") != std::string::npos);

    // long logs are averaged down to max_points per polyline
    std::string big = "step,x\n";
    for (int s = 0; s < 10000; ++s) big += std::to_string(s) + "," + std::to_string(1 + s % 7) + "\n";
    loss_plot_options o;
    o.max_points = 100;
    const std::string b = plot_losses_svg(big, o);
    const auto p0 = b.find("points=\""), p1 = b.find('"', p0 + 8);
    CHECK(count(b.substr(p0, p1 - p0), ",") == 100);
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
