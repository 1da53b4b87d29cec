#include <gam/maps/IniFields.h>
#include <gam/maps/ObservationAdapters.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include "gam/common/Strings.h"

namespace gam::maps::ini
{
std::string sectionContext(const std::string& section) { return "in section '" + section + "':"; }

void checkInSection(const std::string& section, const std::function<void()>& check)
{
	try
	{
		check();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument(sectionContext(section) + " " + e.what());
	}
}

std::string readRaw(const mrpt::config::CConfigFileBase& src, const std::string& section, const std::string& key)
{
	return gam::stripIniComment(src.read_string(section, key, "", false));
}

bool parseBool(const std::string& raw, const ParamInfo& info, const std::string& context)
{
	const std::string l = gam::toLower(raw);
	if (l == "1" || l == "true" || l == "yes" || l == "on") return true;
	if (l == "0" || l == "false" || l == "no" || l == "off") return false;
	throw std::invalid_argument(context + " " + info.key + "=" + raw + " is not a boolean (true/false)");
}

double parseNumber(const std::string& raw, const ParamInfo& info, const std::string& context, bool integer)
{
	char* end = nullptr;
	const double v = std::strtod(raw.c_str(), &end);
	if (raw.empty() || end == raw.c_str() || *end != '\0')
		throw std::invalid_argument(context + " " + info.key + "=" + raw + " is not a number");
	if (integer && (v != std::floor(v) || std::abs(v) > 2e9))
		throw std::invalid_argument(context + " " + info.key + "=" + raw + " is not an integer");
	checkParamRange(info, v, context, raw);
	return v;
}

int parseChoice(const std::string& raw, const ParamInfo& info, const std::string& context)
{
	std::string names;
	for (int i = 0; info.choices && info.choices[i]; i++)
	{
		if (gam::iequals(raw, info.choices[i])) return i;
		names += (i ? " | " : "") + std::string(info.choices[i]);
	}
	// A choice that grew out of a boolean (false | true | ...) keeps taking
	// the boolean spellings its .ini files were written with (0, 1, yes, off).
	const std::string l = gam::toLower(raw);
	const bool boolLike = info.choices && info.choices[0] && info.choices[1] &&
						  std::string(info.choices[0]) == "false" && std::string(info.choices[1]) == "true";
	if (boolLike && (l == "1" || l == "yes" || l == "on")) return 1;
	if (boolLike && (l == "0" || l == "no" || l == "off")) return 0;
	throw std::invalid_argument(context + " " + info.key + "=" + raw + " is not one of " + names);
}

void GridExtent::validate() const
{
	if (!(min_x < max_x) || !(min_y < max_y)) throw std::invalid_argument("needs min_x < max_x and min_y < max_y");
	gam::maps::checkGridSize("the grid", min_x, max_x, min_y, max_y, resolution);
}

}  // namespace gam::maps::ini
