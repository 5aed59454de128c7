// Scenario: a TOML file validated against one schema (keys, types, ranges, units, defaults).
// The schema is the single source of truth: validation, --set, defaults and the key table in
// docs/simulator.md (`mcsim keys`) all come from it.
#pragma once
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace mcsim {

// Bad input: the message names the file, key, value and the allowed range. Exit status 2.
struct ScenarioError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

enum class KeyType { Float, Int, Bool, String, Enum, Float3, Profile };

struct KeySpec {
    const char* key;          // "section.name"
    KeyType type;
    const char* def;          // default as TOML text; "" = derived from the preset (see doc)
    const char* def_ideal;    // default under scenario.profile = "ideal" (nullptr = same)
    double min, max;          // numeric range (Float, Int, Float3, Profile values)
    const char* unit;
    const char* choices;      // Enum: "a|b|c"
    const char* doc;
    const char* shown_default = nullptr;  // docs: the default as shown, when def is "" (derived)
    const char* def_harsh = nullptr;      // default under scenario.profile = "harsh" (nullptr = def;
                                          // "" = derived by the runner, see doc)
};

const std::vector<KeySpec>& scenario_schema();

// Piecewise-linear profile of (t, value) points, held constant outside.
struct Profile {
    std::vector<std::pair<double, double>> pts;
    double at(double t) const;
    bool constant() const { return pts.size() <= 1; }
};

struct Window {
    std::string name;
    double from_s = 0, to_s = 0;
};

class Scenario {
public:
    // Parse + validate a file, then apply --set overrides ("key=value", value in TOML syntax or
    // a bare string). Throws ScenarioError.
    static Scenario load(const std::string& path, const std::vector<std::string>& sets);
    static Scenario from_string(const std::string& toml_text, const std::string& origin,
                                const std::vector<std::string>& sets);

    double f(const std::string& key) const;          // Float / Int
    long i(const std::string& key) const;            // Int
    bool b(const std::string& key) const;
    const std::string& s(const std::string& key) const;  // String / Enum
    bool has(const std::string& key) const;          // explicitly given or with a default
    const Profile& profile(const std::string& key) const;
    std::vector<double> f3(const std::string& key) const;
    const std::vector<Window>& windows() const { return windows_; }
    const std::string& origin() const { return origin_; }

private:
    std::string origin_;
    std::map<std::string, double> num_;
    std::map<std::string, std::string> str_;
    std::map<std::string, Profile> prof_;
    std::map<std::string, std::vector<double>> f3_;
    std::vector<Window> windows_;
};

// A string as it is shown inside quotes in an error message: double quotes, backslashes, control
// characters, NUL and bytes that are not valid UTF-8 escaped (\", \\, \n, \x00, ...), and cut
// after max_chars characters with "…(N bytes)" appended (N: the full length), so that any
// value (a 1 MB key, binary) gives a short message that printf("%s") shows in full.
constexpr size_t kMessageChars = 80;
// escape_quotes = false: '"' and '\\' as they are (text that is not inside quotes).
// Length of the well-formed UTF-8 sequence at s[k] (1 for any ASCII byte; no overlongs, no
// surrogates, <= U+10FFFF), 0 if the bytes there are not valid UTF-8.
size_t utf8_sequence_len(const std::string& s, size_t k);
std::string message_text(const std::string& s, size_t max_chars = kMessageChars, bool escape_quotes = true);
// Largest scenario file Scenario::load reads.
constexpr size_t kMaxScenarioBytes = size_t(1) << 20;

// Markdown table of every key (for docs/simulator.md).
std::string schema_markdown();

}  // namespace mcsim
