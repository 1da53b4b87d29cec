#include "gam/core/Parameters.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace gam
{
namespace
{
std::string number(double v)
{
	std::ostringstream s;
	s << v;
	return s.str();
}
}  // namespace

void checkParamRange(const ParamInfo& info, double value, const std::string& context, const std::string& shown)
{
	if (std::isfinite(value) && value >= info.lo && value <= info.hi) return;
	std::ostringstream s;
	if (!context.empty()) s << context << " ";
	s << info.key << "=" << (shown.empty() ? number(value) : shown) << " is out of range " << number(info.lo) << " to "
	  << number(info.hi);
	if (info.help && *info.help) s << " (" << info.help << ")";
	throw std::invalid_argument(s.str());
}

void requireParams(bool ok, const std::string& context, const std::string& what)
{
	if (!ok) throw std::invalid_argument(context.empty() ? what : context + " " + what);
}

}  // namespace gam
