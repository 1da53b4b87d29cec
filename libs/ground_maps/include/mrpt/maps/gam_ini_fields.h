// Ground-aware mapping for MRPT
// One table per options struct describes every .ini key once: its variable,
// allowed range and meaning. Loading, saving, range checks and unknown-key
// detection all come from that table, so they cannot drift apart.
#pragma once

#include <mrpt/config/CConfigFileBase.h>

#include <cstdint>
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
/** "key = value  ; help" lines, for --print-config style dumps. */
std::string describe(const Fields& f);

}  // namespace gam::ini
