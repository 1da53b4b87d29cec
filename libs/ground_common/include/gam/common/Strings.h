// Ground-aware mapping for MRPT
// The few string helpers every library of the project needs (config keys,
// text files), in one place.
#pragma once

#include <algorithm>
#include <cctype>
#include <string>

namespace gam
{
/** `s` without leading and trailing white space. */
inline std::string trim(const std::string& s)
{
	size_t b = 0, e = s.size();
	while (b < e && std::isspace((unsigned char)s[b])) b++;
	while (e > b && std::isspace((unsigned char)s[e - 1])) e--;
	return s.substr(b, e - b);
}

/** ASCII lower case. */
inline std::string toLower(std::string s)
{
	std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
	return s;
}

/** Case-insensitive (ASCII) equality. */
inline bool iequals(const std::string& a, const std::string& b)
{
	return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
			   return std::tolower((unsigned char)x) == std::tolower((unsigned char)y);
		   });
}

/** An .ini value without a trailing comment (";", "//" or "#", which MRPT's
 * reader leaves in place) and without surrounding blanks. */
inline std::string stripIniComment(std::string raw)
{
	for (const char* c : {";", "//", "#"})
	{
		const auto pos = raw.find(c);
		if (pos != std::string::npos) raw = raw.substr(0, pos);
	}
	return trim(raw);
}

}  // namespace gam
