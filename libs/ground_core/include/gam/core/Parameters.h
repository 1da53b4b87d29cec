// Ground-aware mapping for MRPT
// Every tunable value of the pipeline is described once, next to the member it
// sets: its key (the .ini name; paper Table I names where the paper has one),
// its closed range and its meaning. A parameter struct lists them in
//
//   template <class Self, class Visit>
//   static void forEachParam(Self& self, Visit&& visit)
//   {
//       visit(ParamInfo{"K", 1, 1e6, "RRT-GPD iterations"}, self.iterations);
//       ...
//   }
//
// Self is the struct, const or not, so one list serves validation and saving
// (const) as well as loading (mutable) without a const_cast. The range checks
// of the core (validate()) and the .ini binding of the MRPT plugin
// (gam/maps/IniFields.h) both read these lists: a range cannot drift between
// them. Pure code: no I/O.
#pragma once

#include <string>
#include <type_traits>

namespace gam
{
/** Key, closed range [lo, hi] and meaning of one parameter. */
struct ParamInfo
{
	const char* key;
	double lo, hi;
	const char* help;
	/** For a choice (an enum whose values are 0..n-1): the n names, then
	 * nullptr. The .ini holds the name; lo = 0 and hi = n - 1. */
	const char* const* choices = nullptr;
};

/** The name of choice `v` of `info` ("?" when out of range). */
inline const char* choiceName(const ParamInfo& info, int v)
{
	for (int i = 0; info.choices && info.choices[i]; i++)
		if (i == v) return info.choices[i];
	return "?";
}

/** The paper's method as printed, or this implementation's (the default). */
enum class MethodVariant : int
{
	GroundAware = 0,
	Paper = 1
};
inline constexpr const char* kMethodVariantNames[] = {"ground_aware", "paper", nullptr};

/** Throws std::invalid_argument "<context> <key>=<value> is out of range <lo>
 * to <hi> (<help>)" when `value` is outside [lo, hi] or not finite. `shown` is
 * how the value is printed (the raw .ini text), empty = the number. No square
 * brackets: MRPT's exception wrapper parses them and would split the message. */
void checkParamRange(const ParamInfo& info, double value, const std::string& context, const std::string& shown = {});

/** A parameter's value as a double (a choice: its index). */
template <class T>
double paramAsDouble(const T& v)
{
	if constexpr (std::is_enum_v<T>)
		return double(int(v));
	else
		return double(v);
}

/** Range check of every parameter of `p` (a struct with forEachParam). */
template <class P>
void checkParamRanges(const P& p, const std::string& context)
{
	P::forEachParam(p, [&](const ParamInfo& info, const auto& v) { checkParamRange(info, paramAsDouble(v), context); });
}

/** Throws std::invalid_argument("<context> <what>") unless `ok`: for rules
 * that involve several parameters (z_min < z_max, an odd s_x, ...). */
void requireParams(bool ok, const std::string& context, const std::string& what);

}  // namespace gam
