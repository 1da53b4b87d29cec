// Ground-aware mapping for MRPT -- map evaluation: the reports of the scores (text
// table, JSON, CSV; see Reports.h).
#include "gam/eval/Reports.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>

namespace gam::eval
{
const std::vector<std::string>& reportCategories()
{
	static const std::vector<std::string> c{"negative", "small", "overhang", "large"};
	return c;
}

namespace
{
std::string fmt(const char* f, double v)
{
	char b[64];
	std::snprintf(b, sizeof(b), f, v);
	return b;
}

std::string jsonStr(const std::string& s)
{
	std::string o = "\"";
	for (char c : s)
	{
		if (c == '"' || c == '\\')
			o += '\\', o += c;
		else if ((unsigned char)c < 0x20)
			o += fmt("\\u%04x", double(int(c)));
		else
			o += c;
	}
	return o + "\"";
}

std::string catCell(const Reading& rd, const std::string& cat)
{
	auto it = rd.categories.find(cat);
	if (it == rd.categories.end() || it->second.objects == 0) return "-";
	const auto& c = it->second;
	return std::to_string(c.detected) + "/" + std::to_string(c.objects) + " (" + fmt("%.0f", 100 * c.meanCoverage()) +
		   "%)";
}

std::string countsJson(const CellCounts& c)
{
	return "{\"cells\": " + std::to_string(c.n) + ", \"occupied\": " + std::to_string(c.occupied) +
		   ", \"free\": " + std::to_string(c.free) + ", \"unknown\": " + std::to_string(c.unknown) +
		   ", \"occupied_pct\": " + fmt("%.3f", c.pct(c.occupied)) + ", \"free_pct\": " + fmt("%.3f", c.pct(c.free)) +
		   ", \"unknown_pct\": " + fmt("%.3f", c.pct(c.unknown)) + "}";
}

std::string readingJson(const Reading& rd, const std::string& ind)
{
	std::ostringstream o;
	o << "{\n"
	  << ind << "  \"occupied_if_p_above\": " << fmt("%.6g", rd.occ) << ",\n"
	  << ind << "  \"free_if_p_below\": " << fmt("%.6g", rd.free) << ",\n"
	  << ind << "  \"categories\": {";
	bool first = true;
	for (const auto& [name, c] : rd.categories)
	{
		o << (first ? "\n" : ",\n") << ind << "    " << jsonStr(name) << ": {\"objects\": " << c.objects
		  << ", \"detected\": " << c.detected << ", \"detection_rate\": " << fmt("%.4f", c.detectionRate())
		  << ", \"mean_coverage\": " << fmt("%.4f", c.meanCoverage()) << "}";
		first = false;
	}
	o << "\n" << ind << "  },\n";
	o << ind << "  \"floor\": " << countsJson(rd.floor) << ",\n";
	o << ind << "  \"floor_false_obstacle_pct\": " << fmt("%.3f", rd.floor.pct(rd.floor.occupied)) << ",\n";
	o << ind << "  \"floor_free_pct\": " << fmt("%.3f", rd.floor.pct(rd.floor.free)) << ",\n";
	o << ind << "  \"ramp\": " << countsJson(rd.ramp) << ",\n";
	o << ind << "  \"ramps\": [";
	first = true;
	for (const auto& r : rd.ramps)
	{
		o << (first ? "\n" : ",\n") << ind << "    {\"id\": " << r.id << ", \"name\": " << jsonStr(r.name)
		  << ", \"counts\": " << countsJson(r.cells) << ", \"free_of_known_pct\": " << fmt("%.3f", r.freeOfKnownPct())
		  << "}";
		first = false;
	}
	o << (rd.ramps.empty() ? "" : "\n" + ind + "  ") << "],\n";
	o << ind << "  \"obstacle_cells\": " << countsJson(rd.obstacle) << ",\n";
	o << ind << "  \"objects\": [";
	first = true;
	for (const auto& ob : rd.objects)
	{
		o << (first ? "\n" : ",\n") << ind << "    {\"id\": " << ob.id << ", \"name\": " << jsonStr(ob.name)
		  << ", \"category\": " << jsonStr(ob.category) << ", \"observed_cells\": " << ob.observed
		  << ", \"occupied\": " << ob.occupied << ", \"free\": " << ob.free << ", \"unknown\": " << ob.unknown
		  << ", \"coverage\": " << fmt("%.4f", ob.coverage()) << ", \"detected\": " << (ob.detected ? "true" : "false")
		  << "}";
		first = false;
	}
	o << "\n" << ind << "  ]\n" << ind << "}";
	return o.str();
}
}  // namespace

std::string formatTable(const GroundTruth& gt, const std::vector<MapScore>& scores, const Options& opt)
{
	std::ostringstream o;
	int nObs = 0;
	std::map<std::string, int> nCat;
	if (!scores.empty())
		for (const auto& ob : scores.front().main.objects) nObs++, nCat[ob.category]++;
	o << "ground truth: " << gt.prefix << " (" << gt.nx << "x" << gt.ny << " cells of " << gt.resolution << " m, "
	  << gt.objects.size() << " objects, " << nObs << " observed)\n";
	o << "detected = >= " << std::max(1, opt.min_hits)
	  << " occupied observed cell(s), (coverage %); floor excludes cells within " << opt.tolerance_cells
	  << " cell(s) of an obstacle/drop\n";
	char b[512];
	std::snprintf(
		b, sizeof(b), "%-14s %-10s %-12s %-12s %-12s %-12s %9s %9s %9s %11s\n", "map", "reading", "negative", "small",
		"overhang", "large", "floor_occ%", "floor_free%", "floor_unk%", "obst_cells%");
	o << b;
	for (const auto& s : scores)
		for (const Reading* rd : {&s.main, &s.strict})
		{
			std::snprintf(
				b, sizeof(b), "%-14s %-10s %-12s %-12s %-12s %-12s %9.2f %11.2f %9.2f %11.2f\n", s.name.c_str(),
				rd->name.c_str(), catCell(*rd, "negative").c_str(), catCell(*rd, "small").c_str(),
				catCell(*rd, "overhang").c_str(), catCell(*rd, "large").c_str(), rd->floor.pct(rd->floor.occupied),
				rd->floor.pct(rd->floor.free), rd->floor.pct(rd->floor.unknown),
				rd->obstacle.pct(rd->obstacle.occupied));
			o << b;
		}
	for (const auto& s : scores)
		for (const auto& r : s.main.ramps)
		{
			std::snprintf(
				b, sizeof(b),
				"%-14s ramp %s: %ld cells, occupied %.1f %%, free %.1f %%, unknown %.1f %%; free of known %.1f %%\n",
				s.name.c_str(), r.name.c_str(), r.cells.n, r.cells.pct(r.cells.occupied), r.cells.pct(r.cells.free),
				r.cells.pct(r.cells.unknown), r.freeOfKnownPct());
			o << b;
		}
	if (!scores.empty())
	{
		const auto& s = scores.front();
		o << "floor cells scored: " << s.main.floor.n << " (" << s.excluded_floor << " in the tolerance band)";
		if (s.main.ramp.n) o << ", of which ramp: " << s.main.ramp.n;
		o << "; observed obstacle/drop cells: " << s.main.obstacle.n << "\n";
		for (const auto& [cat, n] : nCat)
			if (std::find(reportCategories().begin(), reportCategories().end(), cat) == reportCategories().end())
				o << "other category '" << cat << "': " << n << " object(s), see the JSON\n";
	}
	return o.str();
}

std::string toJson(const GroundTruth& gt, const std::vector<MapScore>& scores, const Options& opt)
{
	std::ostringstream o;
	o << "{\n  \"ground_truth\": " << jsonStr(gt.prefix) << ",\n  \"gt_resolution\": " << fmt("%.6g", gt.resolution)
	  << ",\n  \"gt_cells\": [" << gt.nx << ", " << gt.ny
	  << "],\n  \"rules\": {\"tolerance_cells\": " << opt.tolerance_cells
	  << ", \"min_hits\": " << std::max(1, opt.min_hits)
	  << ", \"unknown_tolerance\": " << fmt("%.6g", opt.unknown_tolerance) << "},\n  \"maps\": [";
	bool first = true;
	for (const auto& s : scores)
	{
		o << (first ? "\n" : ",\n") << "    {\n      \"name\": " << jsonStr(s.name)
		  << ",\n      \"yaml\": " << jsonStr(s.yamlPath)
		  << ",\n      \"floor_cells_in_tolerance_band\": " << s.excluded_floor
		  << ",\n      \"main\": " << readingJson(s.main, "      ")
		  << ",\n      \"map_server\": " << readingJson(s.strict, "      ") << "\n    }";
		first = false;
	}
	o << "\n  ]\n}\n";
	return o.str();
}

std::string toCsv(const std::vector<MapScore>& scores)
{
	std::ostringstream o;
	o << "map,reading,record,id,category,n,occupied,free,unknown,detected\n";
	for (const auto& s : scores)
		for (const Reading* rd : {&s.main, &s.strict})
		{
			const std::string pre = s.name + "," + (rd == &s.main ? "main" : "map_server") + ",";
			for (const auto& ob : rd->objects)
				o << pre << "object," << ob.id << "," << ob.category << "," << ob.observed << "," << ob.occupied << ","
				  << ob.free << "," << ob.unknown << "," << (ob.detected ? 1 : 0) << "\n";
			auto cc = [&](const char* rec, const CellCounts& c) {
				o << pre << rec << ",0,none," << c.n << "," << c.occupied << "," << c.free << "," << c.unknown
				  << ",0\n";
			};
			cc("floor", rd->floor);
			cc("ramp", rd->ramp);
			cc("obstacle", rd->obstacle);
			for (const auto& r : rd->ramps)
				o << pre << "ramp_object," << r.id << ",ramp," << r.cells.n << "," << r.cells.occupied << ","
				  << r.cells.free << "," << r.cells.unknown << ",0\n";
		}
	return o.str();
}

}  // namespace gam::eval
