// Ground-aware mapping for MRPT
#pragma once

#include <cctype>
#include <sstream>
#include <string>

namespace gam::mapper
{
/** One short line from an exception text. MRPT exceptions carry a multi-line
 * trace ("==== MRPT exception ====", "Message: ...", "Location: ...", a call
 * stack, and nested "Original exception:" blocks): keep the innermost
 * "Message:", without non-printable bytes, at most 300 characters. */
inline std::string conciseError(const std::string& what)
{
	std::istringstream ss(what);
	std::string line, msg, first;
	while (std::getline(ss, line))
	{
		const auto p = line.find("Message:");
		if (p != std::string::npos)
			msg = line.substr(p + 8);
		else if (
			first.empty() && line.find_first_not_of(" \t=") != std::string::npos &&
			line.find("MRPT exception") == std::string::npos)
			first = line;
	}
	std::string s = msg.empty() ? (first.empty() ? what : first) : msg;
	std::string out;
	for (char c : s) out += (std::isprint((unsigned char)c) ? c : '?');
	const auto b = out.find_first_not_of(' ');
	out = b == std::string::npos ? std::string() : out.substr(b);
	if (out.size() > 300) out = out.substr(0, 297) + "...";
	return out;
}
}  // namespace gam::mapper
