// Text as shown in an error message: names and values from files and the command line can hold
// anything (NUL, control bytes, megabytes).
#pragma once
#include <string>

namespace mcsim {

// Control characters, NUL and non-ASCII bytes as \xNN, quotes and backslashes escaped when
// escape_quotes, cut after 80 characters with "...(N bytes)".
std::string shown_text(const std::string& s, bool escape_quotes = true);

}  // namespace mcsim
