// Ground-aware mapping for MRPT
// One table per options struct describes every .ini key once: its variable,
// allowed range and meaning. Loading, saving, range checks and unknown-key
// detection all come from that table, so they cannot drift apart.
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdint>
#include <functional>
#include <string>
#include <variant>
#include <vector>

namespace gam::ini
{
struct Field
{
	std::string key;
	std::variant<double*, float*, int*, bool*> var;
	double lo = -1e300, hi = 1e300;	 ///< closed range [lo, hi]
	std::string help;
};
using Fields = std::vector<Field>;

/** Reads every field present in `section` (absent keys keep their value) and
 * checks its range. Throws std::invalid_argument:
 * "in section 'S': key=value is out of range lo to hi (meaning)" or "... is not a
 * number" (no square brackets: MRPT's exception wrapper would split the message). */
void load(const Fields& f, const mrpt::config::CConfigFileBase& src, const std::string& section);
void save(const Fields& f, mrpt::config::CConfigFileBase& dst, const std::string& section);
/** Range check of the current values; `context` prefixes the message. */
void validate(const Fields& f, const std::string& context);
/** Keys present in `section` that no field names (typos, misplaced keys). */
std::vector<std::string> unknownKeys(
	const Fields& f, const mrpt::config::CConfigFileBase& src, const std::string& section);
/** load(), then `check` (e.g. the struct's validate(), for rules that involve
 * several keys); a std::invalid_argument it throws gets the section in front. */
void loadThenCheck(
	const Fields& f, const mrpt::config::CConfigFileBase& src, const std::string& section,
	const std::function<void()>& check);

/** The `_creationOpts` of a 2D grid map: min_x, max_x, min_y, max_y and
 * resolution, their ranges, min < max, and a cell count that fits in memory. */
template <typename T>
void loadGridExtent(
	const mrpt::config::CConfigFileBase& src, const std::string& section, T& min_x, T& max_x,
	T& min_y, T& max_y, T& resolution);
extern template void loadGridExtent<float>(
	const mrpt::config::CConfigFileBase&, const std::string&, float&, float&, float&, float&, float&);
extern template void loadGridExtent<double>(
	const mrpt::config::CConfigFileBase&, const std::string&, double&, double&, double&, double&,
	double&);

/** Options in a serialized map: a count, then (key, value as double) pairs,
 * so a file written before an option existed still reads (the option keeps
 * its default) and unknown keys from newer files are skipped. */
void writeFields(const Fields& f, mrpt::serialization::CArchive& out);
/** Throws std::runtime_error ("<who>: corrupt stream") on an absurd count. */
void readFields(const Fields& f, mrpt::serialization::CArchive& in, const char* who);

/** "key = value  ; help" lines, for --print-config style dumps. */
std::string describe(const Fields& f);

}  // namespace gam::ini
