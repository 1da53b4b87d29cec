// Ground-aware mapping for MRPT -- map evaluation (see Evaluation.h).
#include "gam/eval/Evaluation.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace gam::eval
{
namespace
{
std::string trim(std::string s)
{
	while (!s.empty() && std::isspace((unsigned char)s.back())) s.pop_back();
	size_t i = 0;
	while (i < s.size() && std::isspace((unsigned char)s[i])) i++;
	return s.substr(i);
}

double toDouble(const std::string& v, const std::string& what)
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

int toInt(const std::string& v, const std::string& what)
{
	const double d = toDouble(v, what);
	if (d != std::floor(d) || std::abs(d) > 1e9) throw Error(what + ": '" + v + "' is not an integer");
	return int(d);
}

std::string dirOf(const std::string& p)
{
	const auto s = p.find_last_of('/');
	return s == std::string::npos ? std::string() : p.substr(0, s + 1);
}

std::vector<std::string> splitCsv(const std::string& line)
{
	std::vector<std::string> out;
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

/** yaml keys of a map_server file (flat "key: value" lines). */
std::map<std::string, std::string> readYamlKeys(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw Error("cannot open " + path);
	std::map<std::string, std::string> kv;
	std::string line;
	while (std::getline(f, line))
	{
		const auto h = line.find('#');
		if (h != std::string::npos) line = line.substr(0, h);
		if (trim(line).empty()) continue;
		const auto c = line.find(':');
		if (c == std::string::npos) throw Error(path + ": not a map_server yaml (line '" + trim(line) + "')");
		kv[trim(line.substr(0, c))] = trim(line.substr(c + 1));
	}
	return kv;
}

void parseOrigin(const std::string& path, const std::string& v, double& x, double& y, double& yaw)
{
	if (v.size() < 2 || v.front() != '[' || v.back() != ']') throw Error(path + ": bad origin '" + v + "'");
	std::string in = v.substr(1, v.size() - 2);
	for (auto& ch : in)
		if (ch == ',') ch = ' ';
	std::istringstream ss(in);
	std::string a, b, c;
	if (!(ss >> a >> b >> c)) throw Error(path + ": bad origin '" + v + "'");
	x = toDouble(a, path + ": origin");
	y = toDouble(b, path + ": origin");
	yaw = toDouble(c, path + ": origin");
}

void readPgm(const std::string& path, int& w, int& h, std::vector<uint8_t>& px)
{
	std::ifstream f(path, std::ios::binary);
	if (!f) throw Error("cannot open " + path);
	auto token = [&]() {
		std::string t;
		char c;
		while (f.get(c))
		{
			if (t.empty() && c == '#')
			{
				std::string dummy;
				std::getline(f, dummy);
				continue;
			}
			if (std::isspace((unsigned char)c))
			{
				if (!t.empty()) break;
				continue;
			}
			t += c;
		}
		return t;
	};
	if (token() != "P5") throw Error(path + ": not a binary PGM (P5)");
	int maxval = 0;
	try
	{
		w = std::stoi(token());
		h = std::stoi(token());
		maxval = std::stoi(token());
	}
	catch (...)
	{
		throw Error(path + ": bad PGM header");
	}
	if (w <= 0 || h <= 0 || w > 100000 || h > 100000) throw Error(path + ": bad PGM size");
	if (maxval != 255) throw Error(path + ": PGM maxval " + std::to_string(maxval) + " (only 255 is supported)");
	px.resize(size_t(w) * size_t(h));
	f.read(reinterpret_cast<char*>(px.data()), std::streamsize(px.size()));
	if (f.gcount() != std::streamsize(px.size())) throw Error(path + ": truncated PGM");
}
}  // namespace

const char* labelName(Label l)
{
	switch (l)
	{
		case Label::Free: return "free";
		case Label::Obstacle: return "obstacle";
		case Label::Drop: return "drop";
		case Label::Unobserved: return "unobserved";
	}
	return "?";
}

double RosMap::pOcc(int col, int rowFromBottom) const
{
	const uint8_t v = pixels[size_t(height - 1 - rowFromBottom) * size_t(width) + size_t(col)];
	const double p = negate ? v / 255.0 : (255.0 - v) / 255.0;
	if (mode == "trinary")
	{
		if (p > occupied_thresh) return 1.0;
		if (p < free_thresh) return 0.0;
		return 0.5;
	}
	return p;
}

RosMap loadRosMap(const std::string& yamlPath)
{
	const auto kv = readYamlKeys(yamlPath);
	RosMap m;
	m.yamlPath = yamlPath;
	auto need = [&](const char* k) -> const std::string& {
		auto it = kv.find(k);
		if (it == kv.end()) throw Error(yamlPath + ": missing key '" + k + "'");
		return it->second;
	};
	std::string image = need("image");
	if (image.size() >= 2 && (image.front() == '"' || image.front() == '\'') && image.back() == image.front())
		image = image.substr(1, image.size() - 2);
	m.imagePath = (!image.empty() && image[0] == '/') ? image : dirOf(yamlPath) + image;
	m.resolution = toDouble(need("resolution"), yamlPath + ": resolution");
	if (!(m.resolution > 0)) throw Error(yamlPath + ": resolution must be > 0");
	parseOrigin(yamlPath, need("origin"), m.origin_x, m.origin_y, m.origin_yaw);
	if (std::abs(m.origin_yaw) > 1e-9) throw Error(yamlPath + ": rotated maps (origin yaw != 0) are not supported");
	if (kv.count("mode")) m.mode = kv.at("mode");
	if (m.mode != "scale" && m.mode != "trinary")
		throw Error(yamlPath + ": mode '" + m.mode + "' is not supported (scale or trinary)");
	if (kv.count("negate"))
	{
		m.negate = toInt(kv.at("negate"), yamlPath + ": negate");
		if (m.negate != 0 && m.negate != 1) throw Error(yamlPath + ": negate must be 0 or 1");
	}
	if (kv.count("occupied_thresh"))
		m.occupied_thresh = toDouble(kv.at("occupied_thresh"), yamlPath + ": occupied_thresh");
	if (kv.count("free_thresh")) m.free_thresh = toDouble(kv.at("free_thresh"), yamlPath + ": free_thresh");
	if (!(m.free_thresh >= 0 && m.free_thresh <= m.occupied_thresh && m.occupied_thresh <= 1))
		throw Error(yamlPath + ": need 0 <= free_thresh <= occupied_thresh <= 1");
	readPgm(m.imagePath, m.width, m.height, m.pixels);
	return m;
}

const GtObject* GroundTruth::object(int id) const
{
	for (const auto& o : objects)
		if (o.id == id) return &o;
	return nullptr;
}

GroundTruth loadGroundTruth(const std::string& prefix)
{
	GroundTruth gt;
	gt.prefix = prefix;
	{
		const std::string yp = prefix + "_gt.yaml";
		const auto kv = readYamlKeys(yp);
		auto it = kv.find("resolution");
		if (it == kv.end()) throw Error(yp + ": missing key 'resolution'");
		gt.resolution = toDouble(it->second, yp + ": resolution");
		if (!(gt.resolution > 0)) throw Error(yp + ": resolution must be > 0");
	}
	{
		const std::string op = prefix + "_gt_objects.csv";
		std::ifstream f(op);
		if (!f) throw Error("cannot open " + op);
		std::string line;
		if (!std::getline(f, line) || splitCsv(line).size() < 4 || trim(splitCsv(line)[0]) != "id" ||
			trim(splitCsv(line)[3]) != "category")
			throw Error(op + ": bad header (expected id,name,type,category,...)");
		int ln = 1;
		while (std::getline(f, line))
		{
			ln++;
			if (trim(line).empty()) continue;
			const auto c = splitCsv(line);
			if (c.size() < 4) throw Error(op + ":" + std::to_string(ln) + ": too few columns");
			GtObject o;
			o.id = toInt(c[0], op + ":" + std::to_string(ln) + ": id");
			o.name = c[1];
			o.type = c[2];
			o.category = trim(c[3]);
			gt.objects.push_back(o);
		}
	}
	const std::string lp = prefix + "_gt_labels.csv";
	std::ifstream f(lp);
	if (!f) throw Error("cannot open " + lp);
	std::string line;
	if (!std::getline(f, line) || trim(line).rfind("ix,iy,x,y,label,object_id", 0) != 0)
		throw Error(lp + ": bad header (expected ix,iy,x,y,label,object_id,category)");
	struct Row
	{
		int ix, iy, id;
		double x, y;
		Label l;
	};
	std::vector<Row> rows;
	int ln = 1;
	while (std::getline(f, line))
	{
		ln++;
		if (trim(line).empty()) continue;
		const auto c = splitCsv(line);
		const std::string at = lp + ":" + std::to_string(ln);
		if (c.size() < 6) throw Error(at + ": too few columns");
		Row r;
		r.ix = toInt(c[0], at + ": ix");
		r.iy = toInt(c[1], at + ": iy");
		r.x = toDouble(c[2], at + ": x");
		r.y = toDouble(c[3], at + ": y");
		const std::string l = trim(c[4]);
		if (l == "free") r.l = Label::Free;
		else if (l == "obstacle") r.l = Label::Obstacle;
		else if (l == "drop") r.l = Label::Drop;
		else if (l == "unobserved") r.l = Label::Unobserved;
		else throw Error(at + ": unknown label '" + l + "'");
		r.id = toInt(c[5], at + ": object_id");
		if (r.ix < 0 || r.iy < 0 || r.ix > 100000 || r.iy > 100000) throw Error(at + ": bad cell index");
		rows.push_back(r);
		gt.nx = std::max(gt.nx, r.ix + 1);
		gt.ny = std::max(gt.ny, r.iy + 1);
	}
	if (rows.empty()) throw Error(lp + ": no cells");
	const size_t n = size_t(gt.nx) * size_t(gt.ny);
	if (rows.size() != n)
		throw Error(lp + ": " + std::to_string(rows.size()) + " rows, expected " + std::to_string(gt.nx) + "x" +
					std::to_string(gt.ny));
	gt.x.assign(n, std::nan(""));
	gt.y.assign(n, std::nan(""));
	gt.label.assign(n, Label::Unobserved);
	gt.objectId.assign(n, 0);
	for (const auto& r : rows)
	{
		const size_t i = gt.idx(r.ix, r.iy);
		if (!std::isnan(gt.x[i])) throw Error(lp + ": cell " + std::to_string(r.ix) + "," + std::to_string(r.iy) + " twice");
		gt.x[i] = r.x;
		gt.y[i] = r.y;
		gt.label[i] = r.l;
		gt.objectId[i] = r.id;
		if (r.id != 0 && !gt.object(r.id))
			throw Error(lp + ": object_id " + std::to_string(r.id) + " is not in " + prefix + "_gt_objects.csv");
	}
	return gt;
}

Resampled resample(const GroundTruth& gt, const RosMap& map)
{
	Resampled r;
	const size_t n = gt.label.size();
	r.pMax.assign(n, 0.5f);
	r.pMin.assign(n, 0.5f);
	const double R = map.resolution, h = 0.5 * gt.resolution;
	// map cell i has its centre at origin + (i + 0.5) R; the cells whose centres are in
	// [a, b) are ceil((a - o)/R - 0.5) .. ceil((b - o)/R - 0.5) - 1.
	auto range = [&](double a, double b, double o, int& i0, int& i1) {
		const double eps = 1e-9;
		i0 = int(std::ceil((a - o) / R - 0.5 - eps));
		i1 = int(std::ceil((b - o) / R - 0.5 - eps)) - 1;
	};
	for (size_t i = 0; i < n; i++)
	{
		const double cx = gt.x[i], cy = gt.y[i];
		int c0, c1, r0, r1;
		range(cx - h, cx + h, map.origin_x, c0, c1);
		range(cy - h, cy + h, map.origin_y, r0, r1);
		float mx = -1, mn = 2;
		bool any = false;
		if (c0 <= c1 && r0 <= r1)
		{
			for (int row = r0; row <= r1; row++)
				for (int col = c0; col <= c1; col++)
				{
					if (!map.inside(col, row)) continue;
					const float p = float(map.pOcc(col, row));
					mx = std::max(mx, p);
					mn = std::min(mn, p);
					any = true;
				}
		}
		else
		{
			const int col = int(std::floor((cx - map.origin_x) / R)), row = int(std::floor((cy - map.origin_y) / R));
			if (map.inside(col, row))
			{
				mx = mn = float(map.pOcc(col, row));
				any = true;
			}
		}
		if (any)
		{
			r.pMax[i] = mx;
			r.pMin[i] = mn;
		}
	}
	return r;
}

std::vector<CellState> classify(const Resampled& r, double occ, double fr)
{
	std::vector<CellState> s(r.pMax.size(), CellState::Unknown);
	for (size_t i = 0; i < s.size(); i++)
	{
		if (r.pMax[i] > occ) s[i] = CellState::Occupied;
		else if (r.pMin[i] < fr) s[i] = CellState::Free;
	}
	return s;
}

const std::vector<std::string>& reportCategories()
{
	static const std::vector<std::string> c{"negative", "small", "overhang", "large"};
	return c;
}

namespace
{
void count(CellCounts& c, CellState s)
{
	c.n++;
	if (s == CellState::Occupied) c.occupied++;
	else if (s == CellState::Free) c.free++;
	else c.unknown++;
}

bool isObstacle(Label l) { return l == Label::Obstacle || l == Label::Drop; }

Reading score(
	const GroundTruth& gt, const std::vector<CellState>& st, const std::vector<uint8_t>& floorMask,
	const Options& opt)
{
	Reading rd;
	std::map<int, ObjectScore> objs;
	for (size_t i = 0; i < st.size(); i++)
	{
		const Label l = gt.label[i];
		if (l == Label::Unobserved) continue;
		if (isObstacle(l))
		{
			count(rd.obstacle, st[i]);
			const int id = gt.objectId[i];
			if (id == 0) continue;  // (the simulator gives every obstacle cell an object)
			auto& o = objs[id];
			o.observed++;
			if (st[i] == CellState::Occupied) o.occupied++;
			else if (st[i] == CellState::Free) o.free++;
			else o.unknown++;
		}
		else if (floorMask[i])
		{
			count(rd.floor, st[i]);
			const GtObject* o = gt.objectId[i] ? gt.object(gt.objectId[i]) : nullptr;
			if (o && o->category == "ramp") count(rd.ramp, st[i]);
		}
	}
	for (auto& [id, o] : objs)
	{
		const GtObject* g = gt.object(id);
		o.id = id;
		o.name = g ? g->name : "";
		o.category = g ? g->category : "none";
		o.detected = o.occupied >= std::max(1, opt.min_hits);
		auto& c = rd.categories[o.category];
		c.objects++;
		c.detected += o.detected ? 1 : 0;
		c.coverageSum += o.coverage();
		rd.objects.push_back(o);
	}
	return rd;
}

std::string baseNoExt(const std::string& p)
{
	const auto s = p.find_last_of('/');
	std::string b = s == std::string::npos ? p : p.substr(s + 1);
	const auto d = b.find_last_of('.');
	return d == std::string::npos ? b : b.substr(0, d);
}
}  // namespace

MapScore evaluate(const GroundTruth& gt, const RosMap& map, const Options& opt)
{
	MapScore ms;
	ms.name = baseNoExt(map.yamlPath);
	ms.yamlPath = map.yamlPath;
	// floor mask: observed free cells farther than tolerance_cells from obstacle/drop cells
	const int t = std::max(0, opt.tolerance_cells);
	std::vector<uint8_t> floorMask(gt.label.size(), 0);
	for (int iy = 0; iy < gt.ny; iy++)
		for (int ix = 0; ix < gt.nx; ix++)
		{
			const size_t i = gt.idx(ix, iy);
			if (gt.label[i] != Label::Free) continue;
			bool near = false;
			for (int dy = -t; dy <= t && !near; dy++)
				for (int dx = -t; dx <= t && !near; dx++)
				{
					const int x = ix + dx, y = iy + dy;
					if (x < 0 || y < 0 || x >= gt.nx || y >= gt.ny) continue;
					near = isObstacle(gt.label[gt.idx(x, y)]);
				}
			if (near) ms.excluded_floor++;
			else floorMask[i] = 1;
		}
	const Resampled r = resample(gt, map);
	const double u = opt.unknown_tolerance;
	ms.main = score(gt, classify(r, 0.5 + u, 0.5 - u), floorMask, opt);
	ms.main.name = "p>0.5";
	ms.main.occ = 0.5 + u;
	ms.main.free = 0.5 - u;
	ms.strict = score(gt, classify(r, map.occupied_thresh, map.free_thresh), floorMask, opt);
	ms.strict.name = "map_server";
	ms.strict.occ = map.occupied_thresh;
	ms.strict.free = map.free_thresh;
	return ms;
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
		if (c == '"' || c == '\\') o += '\\', o += c;
		else if ((unsigned char)c < 0x20) o += fmt("\\u%04x", double(int(c)));
		else o += c;
	}
	return o + "\"";
}

std::string catCell(const Reading& rd, const std::string& cat)
{
	auto it = rd.categories.find(cat);
	if (it == rd.categories.end() || it->second.objects == 0) return "-";
	const auto& c = it->second;
	return std::to_string(c.detected) + "/" + std::to_string(c.objects) + " (" + fmt("%.0f", 100 * c.meanCoverage()) + "%)";
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
	std::snprintf(b, sizeof(b), "%-14s %-10s %-12s %-12s %-12s %-12s %9s %9s %9s %11s\n", "map", "reading", "negative",
				  "small", "overhang", "large", "floor_occ%", "floor_free%", "floor_unk%", "obst_cells%");
	o << b;
	for (const auto& s : scores)
		for (const Reading* rd : {&s.main, &s.strict})
		{
			std::snprintf(b, sizeof(b), "%-14s %-10s %-12s %-12s %-12s %-12s %9.2f %11.2f %9.2f %11.2f\n",
						  s.name.c_str(), rd->name.c_str(), catCell(*rd, "negative").c_str(),
						  catCell(*rd, "small").c_str(), catCell(*rd, "overhang").c_str(),
						  catCell(*rd, "large").c_str(), rd->floor.pct(rd->floor.occupied),
						  rd->floor.pct(rd->floor.free), rd->floor.pct(rd->floor.unknown),
						  rd->obstacle.pct(rd->obstacle.occupied));
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
	  << ",\n  \"gt_cells\": [" << gt.nx << ", " << gt.ny << "],\n  \"rules\": {\"tolerance_cells\": "
	  << opt.tolerance_cells << ", \"min_hits\": " << std::max(1, opt.min_hits)
	  << ", \"unknown_tolerance\": " << fmt("%.6g", opt.unknown_tolerance) << "},\n  \"maps\": [";
	bool first = true;
	for (const auto& s : scores)
	{
		o << (first ? "\n" : ",\n") << "    {\n      \"name\": " << jsonStr(s.name) << ",\n      \"yaml\": "
		  << jsonStr(s.yamlPath) << ",\n      \"floor_cells_in_tolerance_band\": " << s.excluded_floor
		  << ",\n      \"main\": " << readingJson(s.main, "      ") << ",\n      \"map_server\": "
		  << readingJson(s.strict, "      ") << "\n    }";
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
				o << pre << rec << ",0,none," << c.n << "," << c.occupied << "," << c.free << "," << c.unknown << ",0\n";
			};
			cc("floor", rd->floor);
			cc("ramp", rd->ramp);
			cc("obstacle", rd->obstacle);
		}
	return o.str();
}

}  // namespace gam::eval
