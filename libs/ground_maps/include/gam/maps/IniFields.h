// Ground-aware mapping for MRPT
// The .ini binding of parameter structs that list their fields with
// forEachParam (gam/core/Parameters.h): loading, saving, unknown-key
// detection and serialization all walk that one list,
// so a key, its range and its meaning are written down exactly once.
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdint>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "gam/core/Parameters.h"

namespace gam::maps::ini
{
/** The value of `key` in `section` without surrounding blanks and without a
 * trailing comment (";", "//" or "#": MRPT leaves them in place). */
std::string readRaw(const mrpt::config::CConfigFileBase& src, const std::string& section, const std::string& key);

/** Parses `raw` for `info.key`; throws std::invalid_argument "<context>
 * key=raw is not a boolean (true/false)" / "is not a number" / "is not an
 * integer", or the range error of checkParamRange. */
bool parseBool(const std::string& raw, const ParamInfo& info, const std::string& context);
double parseNumber(const std::string& raw, const ParamInfo& info, const std::string& context, bool integer);
/** Index of `raw` among info.choices (case-insensitive; a choice list that
 * begins false, true also takes 0/1, yes/no, on/off); throws
 * std::invalid_argument "<context> key=raw is not one of a | b". */
int parseChoice(const std::string& raw, const ParamInfo& info, const std::string& context);

/** "in section 'S':", the prefix of every message about a key of S. */
std::string sectionContext(const std::string& section);

/** Reads every key of `p` present in `section` (absent keys keep their
 * value), checking each against its range. Rules between keys are the
 * caller's (see loadThenCheck). */
template <class P>
void load(P& p, const mrpt::config::CConfigFileBase& src, const std::string& section)
{
	const std::string ctx = sectionContext(section);
	P::forEachParam(p, [&](const ParamInfo& info, auto& value) {
		using T = std::remove_reference_t<decltype(value)>;
		if (!src.keyExists(section, info.key)) return;
		const std::string raw = readRaw(src, section, info.key);
		if constexpr (std::is_same_v<T, bool>)
			value = parseBool(raw, info, ctx);
		else if constexpr (std::is_enum_v<T>)
			value = T(parseChoice(raw, info, ctx));
		else
			value = T(parseNumber(raw, info, ctx, std::is_integral_v<T>));
	});
}

/** Runs `check` (rules that involve several keys, e.g. a struct's validate());
 * a std::invalid_argument it throws gets "in section 'S':" in front. */
void checkInSection(const std::string& section, const std::function<void()>& check);

/** load(), then checkInSection(section, check). */
template <class P>
void loadThenCheck(
	P& p, const mrpt::config::CConfigFileBase& src, const std::string& section, const std::function<void()>& check)
{
	load(p, src, section);
	checkInSection(section, check);
}

template <class P>
void save(const P& p, mrpt::config::CConfigFileBase& dst, const std::string& section)
{
	P::forEachParam(p, [&](const ParamInfo& info, const auto& value) {
		using T = std::remove_cv_t<std::remove_reference_t<decltype(value)>>;
		if constexpr (std::is_same_v<T, bool>)
			dst.write(section, info.key, std::string(value ? "true" : "false"));
		else if constexpr (std::is_enum_v<T>)
			dst.write(section, info.key, std::string(choiceName(info, int(value))));
		else if constexpr (std::is_floating_point_v<T>)
			dst.write(section, info.key, double(value));
		else
			dst.write(section, info.key, int64_t(value));
	});
}

/** The keys of P, in order. */
template <class P>
std::vector<std::string> keys()
{
	std::vector<std::string> k;
	const P defaults{};
	P::forEachParam(defaults, [&](const ParamInfo& info, const auto&) { k.push_back(info.key); });
	return k;
}

/** Options in a serialized map: a count, then (key, value as double) pairs,
 * so a file written before an option existed still reads (the option keeps
 * its default) and unknown keys from newer files are skipped. */
template <class P>
void write(const P& p, mrpt::serialization::CArchive& out)
{
	uint32_t n = 0;
	P::forEachParam(p, [&](const ParamInfo&, const auto&) { n++; });
	out << n;
	P::forEachParam(
		p, [&](const ParamInfo& info, const auto& value) { out << std::string(info.key) << paramAsDouble(value); });
}

/** Reads what write() wrote (any P: unknown keys are skipped). Throws
 * std::runtime_error ("<who>: corrupt stream") on an absurd count. */
template <class P>
void read(P& p, mrpt::serialization::CArchive& in, const char* who)
{
	uint32_t n;
	in >> n;
	if (n > 10000) throw std::runtime_error(std::string(who) + ": corrupt stream");
	for (uint32_t i = 0; i < n; i++)
	{
		std::string key;
		double v;
		in >> key >> v;
		P::forEachParam(p, [&](const ParamInfo& info, auto& value) {
			using T = std::remove_reference_t<decltype(value)>;
			if (key != info.key) return;
			if constexpr (std::is_same_v<T, bool>)
				value = v != 0;
			else if constexpr (std::is_enum_v<T>)
				value = T(int(v));
			else
				value = T(v);
		});
	}
}

/** The `_creationOpts` of a 2D grid map: min_x, max_x, min_y, max_y and
 * resolution, their ranges, min < max, and a cell count that fits in memory. */
struct GridExtent
{
	double min_x = -10, max_x = 10, min_y = -10, max_y = 10, resolution = 0.05;

	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(ParamInfo{"min_x", -1e5, 1e5, "grid left edge [m]"}, p.min_x);
		visit(ParamInfo{"max_x", -1e5, 1e5, "grid right edge [m]"}, p.max_x);
		visit(ParamInfo{"min_y", -1e5, 1e5, "grid bottom edge [m]"}, p.min_y);
		visit(ParamInfo{"max_y", -1e5, 1e5, "grid top edge [m]"}, p.max_y);
		visit(ParamInfo{"resolution", 1e-3, 100, "d_r, cell size [m]"}, p.resolution);
	}
	/** min < max and at most kMaxGridCells cells; throws std::invalid_argument. */
	void validate() const;
};
/** Loads and checks the extent in `section`, starting from the given values. */
template <typename T>
void loadGridExtent(
	const mrpt::config::CConfigFileBase& src, const std::string& section, T& min_x, T& max_x, T& min_y, T& max_y,
	T& resolution)
{
	GridExtent e{double(min_x), double(max_x), double(min_y), double(max_y), double(resolution)};
	loadThenCheck(e, src, section, [&] { e.validate(); });
	min_x = T(e.min_x), max_x = T(e.max_x), min_y = T(e.min_y), max_y = T(e.max_y), resolution = T(e.resolution);
}

}  // namespace gam::maps::ini
