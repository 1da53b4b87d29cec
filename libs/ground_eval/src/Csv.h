// Ground-aware mapping for MRPT -- map evaluation: private helpers to read the CSV
// inputs (ground truth, per-frame ground truth, snapshot index), shared by the readers.
#pragma once

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "gam/common/Strings.h"
#include "gam/eval/MapReaders.h"

namespace gam::eval::detail
{
using gam::trim;

inline double toDouble(const std::string& v, const std::string& what)
{
	try
	{
		size_t n = 0;
		const double d = std::stod(v, &n);
		if (trim(v.substr(n)).empty() && std::isfinite(d)) return d;
	}
	catch (...)
	{
	}
	throw Error(what + ": '" + v + "' is not a number");
}

inline int toInt(const std::string& v, const std::string& what)
{
	const double d = toDouble(v, what);
	if (d != std::floor(d) || std::abs(d) > 1e9) throw Error(what + ": '" + v + "' is not an integer");
	return int(d);
}

using Columns = std::vector<std::string>;

inline Columns splitCsv(const std::string& line)
{
	Columns out;
	std::string cur;
	for (char c : line)
	{
		if (c == ',')
		{
			out.push_back(cur);
			cur.clear();
		}
		else if (c != '\r')
			cur += c;
	}
	out.push_back(cur);
	return out;
}

/** Reads the CSV file `path`: its first line must pass `headerOk` (else "bad header
 * (expected `expected`)"), then `onRow(columns, "PATH:LINE")` for every non-blank line. */
template <class HeaderOk, class OnRow>
void readCsv(const std::string& path, HeaderOk headerOk, const char* expected, OnRow onRow)
{
	std::ifstream f(path);
	if (!f) throw Error("cannot open " + path);
	std::string line;
	if (!std::getline(f, line) || !headerOk(line)) throw Error(path + ": bad header (expected " + expected + ")");
	int ln = 1;
	while (std::getline(f, line))
	{
		ln++;
		if (trim(line).empty()) continue;
		onRow(splitCsv(line), path + ":" + std::to_string(ln));
	}
}

}  // namespace gam::eval::detail
