#include <mrpt/maps/gam_ini_fields.h>
#include <mrpt/maps/gam_observation_adapters.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace gam::ini
{
namespace
{
double valueOf(const Field& fl)
{
	return std::visit([](auto* p) { return double(*p); }, fl.var);
}

std::string fmt(double v)
{
	std::ostringstream s;
	s << v;
	return s.str();
}

void check(const Field& fl, const std::string& context, const std::string& raw)
{
	const double v = valueOf(fl);
	if (!std::isfinite(v) || v < fl.lo || v > fl.hi)
	{
		std::ostringstream s;
		// No square brackets: MRPT's exception wrapper (MRPT_END) parses them
		// and would split this message across its Location and Message lines.
		s << context << " " << fl.key << "=" << (raw.empty() ? fmt(v) : raw) << " is out of range "
		  << fmt(fl.lo) << " to " << fmt(fl.hi);
		if (!fl.help.empty()) s << " (" << fl.help << ")";
		throw std::invalid_argument(s.str());
	}
}

std::string trim(std::string s)
{
	while (!s.empty() && std::isspace((unsigned char)s.back())) s.pop_back();
	size_t i = 0;
	while (i < s.size() && std::isspace((unsigned char)s[i])) i++;
	return s.substr(i);
}
}  // namespace

void load(const Fields& fields, const mrpt::config::CConfigFileBase& src, const std::string& section)
{
	const std::string ctx = "in section '" + section + "':";
	for (const Field& fl : fields)
	{
		if (!src.keyExists(section, fl.key)) continue;
		std::string raw = trim(src.read_string(section, fl.key, "", false));
		// Strip trailing comments MRPT leaves in place.
		for (const char* c : {";", "//", "#"})
		{
			const auto pos = raw.find(c);
			if (pos != std::string::npos) raw = trim(raw.substr(0, pos));
		}
		std::visit(
			[&](auto* p) {
				using T = std::remove_pointer_t<decltype(p)>;
				if constexpr (std::is_same_v<T, bool>)
				{
					std::string l = raw;
					std::transform(l.begin(), l.end(), l.begin(), ::tolower);
					if (l == "1" || l == "true" || l == "yes" || l == "on")
						*p = true;
					else if (l == "0" || l == "false" || l == "no" || l == "off")
						*p = false;
					else
						throw std::invalid_argument(
							ctx + " " + fl.key + "=" + raw + " is not a boolean (true/false)");
				}
				else
				{
					char* end = nullptr;
					const double v = std::strtod(raw.c_str(), &end);
					if (raw.empty() || end == raw.c_str() || *end != '\0')
						throw std::invalid_argument(ctx + " " + fl.key + "=" + raw + " is not a number");
					if constexpr (std::is_same_v<T, int>)
					{
						if (v != std::floor(v) || std::abs(v) > 2e9)
							throw std::invalid_argument(
								ctx + " " + fl.key + "=" + raw + " is not an integer");
						*p = int(v);
					}
					else
						*p = T(v);
				}
			},
			fl.var);
		check(fl, ctx, raw);
	}
}

void save(const Fields& fields, mrpt::config::CConfigFileBase& dst, const std::string& section)
{
	for (const Field& fl : fields)
		std::visit(
			[&](auto* p) {
				using T = std::remove_pointer_t<decltype(p)>;
				if constexpr (std::is_same_v<T, bool>)
					dst.write(section, fl.key, std::string(*p ? "true" : "false"));
				else
					dst.write(section, fl.key, *p);
			},
			fl.var);
}

void validate(const Fields& fields, const std::string& context)
{
	for (const Field& fl : fields) check(fl, context, "");
}

void loadThenCheck(
	const Fields& f, const mrpt::config::CConfigFileBase& src, const std::string& section,
	const std::function<void()>& check)
{
	load(f, src, section);
	try
	{
		check();
	}
	catch (const std::invalid_argument& e)
	{
		throw std::invalid_argument("in section '" + section + "': " + e.what());
	}
}

template <typename T>
void loadGridExtent(
	const mrpt::config::CConfigFileBase& src, const std::string& section, T& min_x, T& max_x,
	T& min_y, T& max_y, T& resolution)
{
	const Fields f = {
		{"min_x", &min_x, -1e5, 1e5, "grid left edge [m]"},
		{"max_x", &max_x, -1e5, 1e5, "grid right edge [m]"},
		{"min_y", &min_y, -1e5, 1e5, "grid bottom edge [m]"},
		{"max_y", &max_y, -1e5, 1e5, "grid top edge [m]"},
		{"resolution", &resolution, 1e-3, 100, "d_r, cell size [m]"}};
	loadThenCheck(f, src, section, [&] {
		if (!(min_x < max_x) || !(min_y < max_y))
			throw std::invalid_argument("needs min_x < max_x and min_y < max_y");
		gam::mrpt_glue::checkGridSize("the grid", min_x, max_x, min_y, max_y, resolution);
	});
}
template void loadGridExtent<float>(
	const mrpt::config::CConfigFileBase&, const std::string&, float&, float&, float&, float&, float&);
template void loadGridExtent<double>(
	const mrpt::config::CConfigFileBase&, const std::string&, double&, double&, double&, double&,
	double&);

void writeFields(const Fields& fields, mrpt::serialization::CArchive& out)
{
	out << uint32_t(fields.size());
	for (const Field& fl : fields) out << fl.key << valueOf(fl);
}

void readFields(const Fields& fields, mrpt::serialization::CArchive& in, const char* who)
{
	uint32_t n;
	in >> n;
	if (n > 10000) throw std::runtime_error(std::string(who) + ": corrupt stream");
	for (uint32_t i = 0; i < n; i++)
	{
		std::string key;
		double v;
		in >> key >> v;
		for (const Field& fl : fields)
			if (fl.key == key)
				std::visit(
					[v](auto* p) {
						using T = std::remove_pointer_t<decltype(p)>;
						if constexpr (std::is_same_v<T, bool>)
							*p = v != 0;
						else
							*p = T(v);
					},
					fl.var);
	}
}

std::vector<std::string> unknownKeys(
	const Fields& fields, const mrpt::config::CConfigFileBase& src, const std::string& section)
{
	std::vector<std::string> keys, out;
	src.getAllKeys(section, keys);
	for (const auto& k : keys)
		if (std::none_of(fields.begin(), fields.end(), [&](const Field& f) { return f.key == k; }))
			out.push_back(k);
	return out;
}

std::string describe(const Fields& fields)
{
	std::ostringstream s;
	for (const Field& fl : fields)
	{
		s << fl.key << " = ";
		std::visit(
			[&](auto* p) {
				using T = std::remove_pointer_t<decltype(p)>;
				if constexpr (std::is_same_v<T, bool>)
					s << (*p ? "true" : "false");
				else
					s << *p;
			},
			fl.var);
		s << "\t; " << fmt(fl.lo) << " to " << fmt(fl.hi) << ": " << fl.help << "\n";
	}
	return s.str();
}

}  // namespace gam::ini
