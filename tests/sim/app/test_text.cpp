// Text that mcsim builds: JSON strings in metrics.json (json_string, Metrics::json) and the
// quoting of keys and values in scenario error messages (message_text, Scenario errors).
#include <gtest/gtest.h>

#include <string>

#include "metrics.hpp"
#include "scenario.hpp"

using namespace mcsim;

TEST(JsonString, EscapesQuotesBackslashesAndControls) {
    EXPECT_EQ(json_string("plain"), "\"plain\"");
    EXPECT_EQ(json_string(""), "\"\"");
    EXPECT_EQ(json_string("a\"b"), "\"a\\\"b\"");
    EXPECT_EQ(json_string("a\\b"), "\"a\\\\b\"");
    EXPECT_EQ(json_string("l1\nl2\t\r\b\f"), "\"l1\\nl2\\t\\r\\b\\f\"");
    EXPECT_EQ(json_string(std::string("a\0b", 3)), "\"a\\u0000b\"");
    EXPECT_EQ(json_string("\x1f\x7f"), "\"\\u001f\\u007f\"");
}

TEST(JsonString, KeepsValidUtf8AndReplacesInvalidBytes) {
    EXPECT_EQ(json_string("\xc2\xb5s \xe2\x80\xa6 \xf0\x9f\x98\x80"), "\"\xc2\xb5s \xe2\x80\xa6 \xf0\x9f\x98\x80\"");
    EXPECT_EQ(json_string("\xff"), "\"\\ufffd\"");
    EXPECT_EQ(json_string("\xc3"), "\"\\ufffd\"");                  // truncated sequence
    EXPECT_EQ(json_string("\xc0\xaf"), "\"\\ufffd\\ufffd\"");       // overlong
    EXPECT_EQ(json_string("\xed\xa0\x80"), "\"\\ufffd\\ufffd\\ufffd\"");  // surrogate
}

TEST(MetricsJson, WindowNamesFaultsAndExtrasAreEscaped) {
    const Scenario sc = Scenario::from_string(
        "[scenario]\nduration_s = 0.1\n[[metrics.window]]\nname = 'w\"1\\'\nfrom_s = 0.0\nto_s = 0.05\n", "(test)", {});
    Metrics m(sc);
    const std::string j = m.json({"OVER\"CURRENT"}, "RU\nN", {{"scenario", json_string("a\"b")}, {"k\"", "1"}});
    EXPECT_NE(j.find("\"w\\\"1\\\\\": {"), std::string::npos) << j;
    EXPECT_NE(j.find("\"faults\": [\"OVER\\\"CURRENT\"]"), std::string::npos) << j;
    EXPECT_NE(j.find("\"final_state\": \"RU\\nN\""), std::string::npos) << j;
    EXPECT_NE(j.find("\"scenario\": \"a\\\"b\""), std::string::npos) << j;
    EXPECT_NE(j.find("\"k\\\"\": 1"), std::string::npos) << j;
}

TEST(MessageText, EscapesAndShortens) {
    EXPECT_EQ(message_text("abc"), "abc");
    EXPECT_EQ(message_text(std::string("a\0b\n\"\\", 6)), "a\\x00b\\n\\\"\\\\");
    EXPECT_EQ(message_text("\xff\xc2\xb5"), "\\xff\xc2\xb5");
    const std::string big(1000000, 'k');
    const std::string m = message_text(big);
    EXPECT_LT(m.size(), 120u);
    EXPECT_NE(m.find("\xe2\x80\xa6(1000000 bytes)"), std::string::npos) << m;
}

namespace {
std::string scenario_error(const std::string& text, const std::vector<std::string>& sets = {}) {
    try {
        Scenario::from_string(text, "(test)", sets);
    } catch (const ScenarioError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no error";
    return {};
}
}  // namespace

TEST(ScenarioErrors, NulBytesAreShownAndHugeKeysAreCut) {
    const std::string nul = scenario_error("[scenario]\nduration_s = \"x\\u0000y\"\n");
    EXPECT_NE(nul.find("\"x\\x00y\""), std::string::npos) << nul;
    EXPECT_EQ(nul.find('\0'), std::string::npos);
    EXPECT_NE(nul.find("allowed range"), std::string::npos) << nul;

    const std::string key = scenario_error("[scenario]\n" + std::string(1000000, 'k') + " = 1\n");
    EXPECT_LT(key.size(), 2048u) << key.size();
    EXPECT_NE(key.find("unknown key"), std::string::npos) << key.substr(0, 300);
    EXPECT_NE(key.find("bytes)"), std::string::npos) << key.substr(0, 300);

    const std::string val = scenario_error("[scenario]\nduration_s = \"" + std::string(1000000, 'v') + "\"\n");
    EXPECT_LT(val.size(), 2048u) << val.size();

    std::string arr = "[scenario]\nduration_s = [";
    for (int k = 0; k < 100000; ++k) arr += "1.5, ";
    arr += "1]\n";
    const std::string a = scenario_error(arr);
    EXPECT_LT(a.size(), 2048u) << a.size();

    const std::string set = scenario_error("", {std::string(1000000, 's') + ".x=1"});
    EXPECT_LT(set.size(), 2048u) << set.size();
}
