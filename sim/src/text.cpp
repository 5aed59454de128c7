#include "mcsim/text.hpp"

namespace mcsim {

std::string shown_text(const std::string& s, bool escape_quotes)
{
    static const char* const kHex = "0123456789abcdef";
    std::string o;
    size_t k = 0;
    for (; k < s.size() && k < 80; ++k) {
        const unsigned char c = static_cast<unsigned char>(s[k]);
        if (escape_quotes && (c == '"' || c == '\\')) {
            o += '\\';
            o += char(c);
        } else if (c >= 0x20 && c < 0x7f) {
            o += char(c);
        } else {
            o += "\\x";
            o += kHex[c >> 4];
            o += kHex[c & 15];
        }
    }
    if (k < s.size()) o += "...(" + std::to_string(s.size()) + " bytes)";
    return o;
}

}  // namespace mcsim
