// Ground-aware mapping for MRPT -- map evaluation: private helpers for file paths,
// shared by the readers (folder of a yaml) and the scoring (name of a map).
#pragma once

#include <string>

namespace gam::eval::detail
{
/** Where the file name of path `p` starts: after its last '/' (0 when there is none). */
inline size_t fileNameStart(const std::string& p)
{
	const auto s = p.find_last_of('/');
	return s == std::string::npos ? 0 : s + 1;
}

/** The folder of `p` with its trailing '/', or "" for a bare file name. */
inline std::string dirOf(const std::string& p) { return p.substr(0, fileNameStart(p)); }

/** The file name of `p` without its last extension ("maps/a.b.yaml" -> "a.b"). */
inline std::string baseNoExt(const std::string& p)
{
	const std::string b = p.substr(fileNameStart(p));
	const auto d = b.find_last_of('.');
	return d == std::string::npos ? b : b.substr(0, d);
}

}  // namespace gam::eval::detail
