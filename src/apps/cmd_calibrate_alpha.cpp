/* shadyloc calibrate-alpha: alpha (beta = 1 - alpha) and the 8-bit mapping of
 * the invariant transform from data (docs/calibration.md). */
#include "Command.h"
#include "CommandLine.h"

#include <shadyloc/eval/Figures.h>
#include <shadyloc/filters/Filters.h>
#include <shadyloc/image/CameraSuitability.h>
#include <shadyloc/image/InvariantCalibration.h>
#include <shadyloc/io/ImageFile.h>
#include <shadyloc/io/OutputTransaction.h>
#include <shadyloc/io/Rawlog.h>

#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <regex>
#include <sstream>

namespace fs = std::filesystem;
using namespace shadyloc::image;

namespace cmd_calibrate_alpha
{
cv::Mat readColour(const std::string& path)
{
	if (!fs::is_regular_file(path)) throw std::runtime_error("'" + path + "': no such image file");
	// The checked reader: cv::imread returns a cut JPEG with grey rows.
	const cv::Mat img = shadyloc::io::readImageFile(path, cv::IMREAD_UNCHANGED);
	if (img.type() != CV_8UC3)
		throw std::runtime_error(
			"'" + path + "': needs an 8-bit 3-channel colour image (got " + std::to_string(img.channels()) +
			" channel(s), depth " + std::to_string(img.depth()) + ")");
	return img;
}

std::pair<std::string, std::string> splitComma(const std::string& s, const std::string& opt)
{
	const auto c = s.find(',');
	if (c == std::string::npos || c == 0 || c + 1 == s.size())
		throw std::invalid_argument(opt + ": expected two paths separated by ',', got '" + s + "'");
	return {s.substr(0, c), s.substr(c + 1)};
}

bool isImageFile(const fs::path& p)
{
	auto e = p.extension().string();
	std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
	return e == ".png" || e == ".jpg" || e == ".jpeg" || e == ".ppm" || e == ".bmp" || e == ".tif" || e == ".tiff";
}

/** The image files of a folder, sorted. */
std::vector<fs::path> imageFilesIn(const std::string& dir)
{
	std::vector<fs::path> files;
	for (const auto& e : fs::directory_iterator(dir))
		if (e.is_regular_file() && isImageFile(e.path())) files.push_back(e.path());
	std::sort(files.begin(), files.end());
	return files;
}

/** <stem>_free.<ext> with <stem>_shadow*.<ext> beside it. */
std::vector<TShadowPair> pairsInDir(const std::string& dir)
{
	if (!fs::is_directory(dir)) throw std::runtime_error("--pairs '" + dir + "': not a directory");
	const std::vector<fs::path> files = imageFilesIn(dir);
	const std::regex re("(.+)_shadow[^.]*");
	std::vector<TShadowPair> pairs;
	for (const auto& f : files)
	{
		std::smatch m;
		const std::string stem = f.stem().string();
		if (!std::regex_match(stem, m, re)) continue;
		const fs::path freePath = f.parent_path() / (m[1].str() + "_free" + f.extension().string());
		if (!fs::exists(freePath))
			throw std::runtime_error("--pairs: '" + f.string() + "' has no '" + freePath.filename().string() + "' beside it");
		pairs.push_back({stem, readColour(freePath.string()), readColour(f.string())});
	}
	if (pairs.empty())
		throw std::runtime_error("--pairs '" + dir + "': no <name>_free.<ext> / <name>_shadow*.<ext> image pairs");
	return pairs;
}

/** "WxH px, fx=.. fy=.. cx=.. cy=.." of a camera observation's (left) camera. */
std::string describeCamera(const cv::Mat& m, const mrpt::img::TCamera& c)
{
	std::ostringstream s;
	s << m.cols << "x" << m.rows << " px, fx=" << c.fx() << " fy=" << c.fy() << " cx=" << c.cx() << " cy=" << c.cy();
	return s.str();
}

/** The colour frames of a rawlog (left eye); `camera`, if given, gets the
 * first frame's camera (describeCamera). */
std::vector<cv::Mat> framesOfRawlog(
	const std::string& path, const std::string& label, int maxFrames, int every, std::string* camera = nullptr)
{
	std::vector<cv::Mat> out;
	shadyloc::io::RawlogReader reader(path);
	int seen = 0;
	while (auto obj = reader.next())
	{
		for (const auto& obs : shadyloc::io::observationsIn(obj))
		{
			if (!label.empty() && obs->sensorLabel != label) continue;
			std::vector<const mrpt::img::CImage*> eyes;
			const mrpt::img::TCamera* cam = nullptr;
			if (auto* st = dynamic_cast<mrpt::obs::CObservationStereoImages*>(obs.get()))
				eyes.push_back(&st->imageLeft), cam = &st->leftCamera;
			else if (auto* im = dynamic_cast<mrpt::obs::CObservationImage*>(obs.get()))
				eyes.push_back(&im->image), cam = &im->cameraParams;
			else
				continue;
			if (seen++ % every != 0) continue;
			shadyloc::io::loadExternalImages(*obs);
			const cv::Mat& m = eyes[0]->asCvMatRef();
			if (m.type() != CV_8UC3)
				throw std::runtime_error(reader.where(
					"sensor '" + obs->sensorLabel + "': needs 8-bit colour images, this one has " +
					std::to_string(m.channels()) + " channel(s)"));
			if (camera && out.empty()) *camera = describeCamera(m, *cam);
			out.push_back(m.clone());
			if (maxFrames > 0 && int(out.size()) >= maxFrames) return out;
		}
	}
	if (out.empty())
		throw std::runtime_error(
			"'" + path + "': no camera observations" + (label.empty() ? "" : " labelled '" + label + "'"));
	return out;
}

/** What a method's items are, for messages. */
const char* itemsOf(const std::string& method)
{
	if (method == "entropy" || method == "edges") return " images";
	if (method == "runs") return " matched frame pairs";
	return " pairs";
}

std::string fmt(double v, int prec = 4)
{
	std::ostringstream s;
	s << std::fixed << std::setprecision(prec) << v;
	return s.str();
}

/** Every input declared to the transaction, before any is read: no output
 * may be an input, and none may lie in a folder whose images are all read
 * (a second run would take the first one's curve PNG as an image). */
void declareInputs(
	shadyloc::io::OutputTransaction& tx, const std::string& pairsDir, const std::string& imagesDir,
	const std::vector<std::pair<std::string, std::vector<std::string>>>& lists)
{
	if (!pairsDir.empty()) tx.addListedFolder(pairsDir, "--pairs folder");
	if (!imagesDir.empty()) tx.addListedFolder(imagesDir, "--images folder");
	for (const auto& [opt, values] : lists)
		for (const auto& v : values)
		{
			const auto c = v.find(',');
			tx.addInput(v.substr(0, c), opt + " input");
			if (c != std::string::npos) tx.addInput(v.substr(c + 1), opt + " input");
		}
}

void writeText(const std::string& path, const std::string& text)
{
	std::ofstream f(path);
	f << text;
	f.close();
	if (!f) throw std::runtime_error("'" + path + "': cannot write");
}

/** The curves (one panel per method) as a PNG through gnuplot (eval::runGnuplot). */
void plotCurves(
	const std::vector<TAlphaCurve>& curves, const std::string& csvPath, const std::string& pngPath,
	double defaultAlpha, const std::string& title)
{
	std::ostringstream g;
	g << "set datafile separator ','\n"
	  << "set multiplot layout " << curves.size() << ",1 title " << shadyloc::eval::gnuplotQuote(title) << "\n"
	  << "set xlabel 'alpha (beta = 1 - alpha)'\nset grid\nset key top right\n";
	for (size_t i = 0; i < curves.size(); i++)
	{
		const auto& c = curves[i];
		g << "unset object\nunset arrow\n"
		  << "set ylabel \"" << c.method << "\"\n"
		  << "set title \"" << c.method << ": " << c.costName << "; alpha = " << fmt(c.best, 3);
		if (c.bootstrapRounds > 0) g << ", 95% interval [" << fmt(c.ciLow, 3) << ", " << fmt(c.ciHigh, 3) << "]";
		g << " (" << c.items << itemsOf(c.method) << ")\"\n";
		if (c.bootstrapRounds > 0 && c.ciHigh > c.ciLow)
			g << "set object 1 rect from " << c.ciLow << ", graph 0 to " << c.ciHigh
			  << ", graph 1 fc rgb '#cce0ff' fs solid 0.6 noborder behind\n";
		g << "set arrow 1 from " << c.best << ", graph 0 to " << c.best << ", graph 1 nohead lc rgb '#0050c0' lw 2\n"
		  << "set arrow 2 from " << defaultAlpha << ", graph 0 to " << defaultAlpha
		  << ", graph 1 nohead lc rgb '#c03000' dt 2 lw 1.5\n"
		  << "plot " << shadyloc::eval::gnuplotQuote(csvPath) << " using 1:" << (i + 2)
		  << " every ::1 with lines lw 2 lc rgb '#202020' title '"
		  << c.method << "', NaN with lines lc rgb '#0050c0' lw 2 title 'estimate', "
		  << "NaN with lines lc rgb '#c03000' dt 2 title 'default alpha " << fmt(defaultAlpha, 3) << "'\n";
	}
	g << "unset multiplot\n";
	try
	{
		shadyloc::eval::runGnuplot(g.str(), pngPath, 900, static_cast<unsigned>(300 * curves.size()));
	}
	catch (const std::exception& e)
	{
		throw std::runtime_error(std::string(e.what()) + "; or pass --no-plot");
	}
}

/** What the command line names as data. */
struct TInputArgs
{
	std::string pairsDir;
	std::vector<std::string> pairs, sameView, runs, images;
	std::string imagesDir;
	std::vector<std::string> rawlogs;
	std::string sensor;
	int maxFrames = 0, every = 1;
};

/** The data read, by kind. */
struct TInputs
{
	std::vector<TShadowPair> shadowPairs;
	std::vector<TSameViewPair> viewPairs;
	std::vector<cv::Mat> plain;	 //!< ordinary images and rawlog frames
	std::vector<TChromaChanges> runChanges;	 //!< matched points of --runs
	std::vector<cv::Mat> runFrames;	 //!< the frames of --runs
	bool hasRuns = false;

	/** Every image given: the entropy and edges methods and the mapping use
	 * them all (pairs are images too). */
	std::vector<cv::Mat> allImages() const
	{
		std::vector<cv::Mat> all = plain;
		for (const auto& p : shadowPairs) all.push_back(p.free), all.push_back(p.shadow);
		for (const auto& p : viewPairs) all.push_back(p.a), all.push_back(p.b);
		all.insert(all.end(), runFrames.begin(), runFrames.end());
		return all;
	}
};

std::vector<cv::Mat> imagesOfDir(const std::string& dir)
{
	if (!fs::is_directory(dir)) throw std::runtime_error("--images '" + dir + "': not a directory");
	const std::vector<fs::path> files = imageFilesIn(dir);
	if (files.empty()) throw std::runtime_error("--images '" + dir + "': no image files");
	std::vector<cv::Mat> out;
	for (const auto& f : files) out.push_back(readColour(f.string()));
	return out;
}

/** One --runs pair A,B: A's frames (every --every-th) matched in all of B's,
 * both limited by --max-frames. Every pair must be of the first pair's
 * camera (`runsCamera`, `runsFirst`: set by the first pair). */
void readRunPair(
	const std::string& s, const TInputArgs& a, const TCalibrationInput& in, std::string& runsCamera,
	std::string& runsFirst, TInputs& out)
{
	const auto [ra, rb] = splitComma(s, "--runs");
	std::string camA, camB;
	auto fa = framesOfRawlog(ra, a.sensor, a.maxFrames, a.every, &camA);
	auto fb = framesOfRawlog(rb, a.sensor, a.maxFrames, 1, &camB);
	// Matching across cameras compares chromaticities of two sensors, not
	// of two lights: the estimate would be of the cameras' difference.
	if (camA != camB)
		throw std::invalid_argument(
			"--runs " + s + ": the runs are of different cameras ('" + ra + "': " + camA + "; '" + rb + "': " + camB +
			"); two runs of one camera are needed");
	// Every --runs pair goes into one estimate: one camera for all of them.
	if (runsCamera.empty()) runsCamera = camA, runsFirst = s;
	else if (camA != runsCamera)
		throw std::invalid_argument(
			"--runs " + s + ": its camera (" + camA + ") is not that of --runs " + runsFirst + " (" + runsCamera +
			"); the estimate pools every pair, so they must be of one camera");
	std::cout << "--runs " << s << ": matching " << fa.size() << " frames of '" << ra << "' in the " << fb.size()
			  << " of '" << rb << "'\n";
	size_t done = 0;
	auto items = correspondencesAcrossRuns(fa, fb, in, {}, [&](const std::string& line) {
		std::cout << "  [" << ++done << "/" << fa.size() << "] " << line << std::endl;
	});
	std::cout << "  " << items.size() << " of " << fa.size() << " frames matched\n";
	const std::string prefix = fs::path(ra).stem().string() + "/" + fs::path(rb).stem().string() + " ";
	for (auto& it : items) it.name = prefix + it.name, out.runChanges.push_back(std::move(it));
	for (auto* f : {&fa, &fb})
		for (auto& m : *f) out.runFrames.push_back(std::move(m));
}

TInputs readInputs(const TInputArgs& a, const TCalibrationInput& in)
{
	TInputs out;
	if (!a.pairsDir.empty()) out.shadowPairs = pairsInDir(a.pairsDir);
	for (const auto& s : a.pairs)
	{
		const auto [f, sh] = splitComma(s, "--pair");
		out.shadowPairs.push_back({fs::path(sh).stem().string(), readColour(f), readColour(sh)});
	}
	for (const auto& s : a.sameView)
	{
		const auto [x, y] = splitComma(s, "--same-view");
		out.viewPairs.push_back(
			{fs::path(x).stem().string() + "/" + fs::path(y).stem().string(), readColour(x), readColour(y)});
	}
	for (const auto& f : a.images) out.plain.push_back(readColour(f));
	if (!a.imagesDir.empty())
		for (auto& m : imagesOfDir(a.imagesDir)) out.plain.push_back(std::move(m));
	for (const auto& r : a.rawlogs)
		for (auto& m : framesOfRawlog(r, a.sensor, a.maxFrames, a.every)) out.plain.push_back(std::move(m));
	std::string runsCamera, runsFirst;
	for (const auto& s : a.runs) readRunPair(s, a, in, runsCamera, runsFirst, out);
	out.hasRuns = !a.runs.empty();
	if (out.shadowPairs.empty() && out.viewPairs.empty() && out.plain.empty() && out.runFrames.empty())
		throw std::invalid_argument("no data: give --pairs/--pair, --same-view, --runs, --image/--images or --rawlog");
	return out;
}

/** Every image file the command line names, folders listed: what the JPEG
 * header check reads (rawlog frames have no file of their own). */
std::vector<std::string> imageFilesGiven(const TInputArgs& a)
{
	std::vector<std::string> out;
	for (const auto* dir : {&a.pairsDir, &a.imagesDir})
		if (!dir->empty())
			for (const auto& f : imageFilesIn(*dir)) out.push_back(f.string());
	for (const auto& [opt, list] : {std::pair{"--pair", &a.pairs}, {"--same-view", &a.sameView}})
		for (const auto& s : *list)
		{
			const auto [x, y] = splitComma(s, opt);
			out.push_back(x), out.push_back(y);
		}
	out.insert(out.end(), a.images.begin(), a.images.end());
	return out;
}

/** The suitability verdict (CameraSuitability.h) on the images at p's alpha and beta. */
TSuitabilityVerdict judgeInputs(
	const TInputArgs& a, const TInputs& data, const std::vector<cv::Mat>& all, const TCalibrationInput& in,
	const InvariantParams& p, const std::vector<TAlphaCurve>& curves, const TAlphaCurve* chosen,
	const TAlphaSearch& search)
{
	TSuitabilityEvidence e;
	e.gridMeasured = true;
	e.grid = blockGridOf(all, p);
	e.saturated = saturatedShare(all, in);
	if (!data.shadowPairs.empty()) e.tone = toneCurveDrifts(data.shadowPairs, in);
	for (const auto& f : imageFilesGiven(a))
	{
		const std::string sub = jpegChromaSubsampling(f);
		if (sub.empty()) continue;
		e.jpegFiles++;
		if (sub != "4:4:4") e.subsampledFiles.push_back(fs::path(f).filename().string() + " " + sub);
	}
	e.curves = curves;
	e.chosenMethod = chosen ? chosen->method : "";
	e.search = search;
	return judgeSuitability(e);
}

void printSuitability(const TSuitabilityVerdict& v)
{
	std::cout << "\nsuitability of these images for the invariant channel (docs/calibration.md):\n";
	for (const auto& c : v.checks) std::cout << "  " << c << "\n";
	for (const auto& r : v.reasons)
		std::cout << "reason: " << r.code << " (" << toString(r.severity) << "): " << r.text << "\n";
}

/** Every method's curve that has data; the first is the preferred one (auto). */
std::vector<TAlphaCurve> estimateCurves(
	const TInputs& data, const std::vector<cv::Mat>& all, const TCalibrationInput& in, const TAlphaSearch& search,
	int edgeStep, double edgeMaxChroma)
{
	std::vector<TAlphaCurve> curves;
	std::vector<std::string> skipped;
	if (!data.shadowPairs.empty())
		curves.push_back(alphaFromShadowPairs(data.shadowPairs, in, search, 0.01, &skipped));
	if (!data.viewPairs.empty()) curves.push_back(alphaFromSameView(data.viewPairs, in, search, 0.03, &skipped));
	// Matched points, not whole images: a smaller minimum per frame pair.
	if (data.hasRuns) curves.push_back(alphaFromChromaChanges(data.runChanges, search, 0.03, 50, "runs", &skipped));
	curves.push_back(alphaByEdgeDirections(edgeSamples(all, in, edgeStep), search, edgeMaxChroma));
	curves.push_back(alphaByEntropy(chromaSamples(all, in), search));
	for (const auto& s : skipped) std::cout << "skipped: " << s << "\n";
	return curves;
}

const TAlphaCurve* chooseCurve(const std::vector<TAlphaCurve>& curves, const std::string& want)
{
	if (want == "auto") return &curves.front();
	for (const auto& c : curves)
		if (c.method == want) return &c;
	throw std::invalid_argument(
		"--method " + want + ": that method had no data (pairs: --pairs/--pair; same-view: --same-view; runs: --runs)");
}

void printEstimates(const std::vector<TAlphaCurve>& curves, const TAlphaCurve* chosen, const TAlphaSearch& search)
{
	std::cout << "\nalpha estimates (beta = 1 - alpha; 95 % bootstrap interval over "
			  << (search.bootstrapRounds > 0 ? std::to_string(search.bootstrapRounds) + " resamplings" : "none")
			  << "):\n";
	for (const auto& c : curves)
		std::cout << "  " << std::left << std::setw(10) << c.method << " alpha " << fmt(c.best) << "  ["
				  << fmt(c.ciLow) << ", " << fmt(c.ciHigh) << "]  from " << c.items << itemsOf(c.method)
				  << (&c == chosen ? "   <- used" : "") << "\n";
}

std::string mappingShape(const InvariantParams& p, double minSpan)
{
	if (p.hasCompressedTails())
		return "tails compressed (a linear mapping gave the 1st-99th percentiles fewer than " + fmt(minSpan, 0) +
			   " levels): linear between grey levels " + fmt(p.knee_low, 2) + " and " + fmt(p.knee_high, 2) +
			   ", slope " + fmt(p.tail_slope_low, 4) + " beyond";
	if (minSpan > 0) return "linear mapping (it gives the 1st-99th percentiles at least " + fmt(minSpan, 0) + " levels)";
	return "linear mapping (--min-span 0)";
}

/** Prints the calibrated mapping p and its clipping against the default
 * mapping at the same alpha and beta and the paper's; returns p's. */
TMappingStats reportMapping(
	const std::vector<cv::Mat>& all, const InvariantParams& p, const InvariantParams& pDefault,
	const TCalibrationInput& in, double minSpan, Suitability verdict)
{
	const auto stCal = mappingStats(all, p, in.stride);
	const auto stDef = mappingStats(all, pDefault, in.stride);
	auto pPaper = InvariantParams::FromAlphaBeta(0.4800, 0.5065);
	pPaper.order = in.order, pPaper.linearisation = in.linearisation, pPaper.gamma = in.gamma;
	const auto stPaper = mappingStats(all, pPaper, in.stride);
	// Never a confident number from data that do not suit the model.
	std::cout << (verdict == Suitability::Suitable
					  ? "\nresult: alpha = "
					  : "\nresult, NOT a confident estimate (verdict " + toString(verdict) + ", reasons above): alpha = ")
			  << fmt(p.alpha) << ", beta = 1 - alpha = " << fmt(p.beta)
			  << "\n  wavelength form: 1/l2 = alpha/l1 + beta/l3, e.g. green peak "
			  << fmt(equivalentGreenPeak(p.alpha, 470, 620), 1) << " nm for blue 470 / red 620 nm"
			  << "\n  8-bit mapping: scale = " << fmt(p.scale, 3) << " grey levels per log unit, offset = "
			  << fmt(p.offset) << "\n  " << mappingShape(p, minSpan) << "\n\nclipping over the " << all.size()
			  << " calibration images (share of pixels at 0 or 255; 1st-99th percentile span):\n"
			  << "  calibrated mapping          " << fmt(100 * stCal.clipped(), 2) << " %  (low "
			  << fmt(100 * stCal.clipLow, 2) << ", high " << fmt(100 * stCal.clipHigh, 2) << "), span "
			  << fmt(stCal.span(), 1) << " grey levels\n"
			  << "  default mapping, this alpha " << fmt(100 * stDef.clipped(), 2) << " %, span "
			  << fmt(stDef.span(), 1) << "\n"
			  << "  paper's alpha/beta/mapping  " << fmt(100 * stPaper.clipped(), 2) << " %, span "
			  << fmt(stPaper.span(), 1) << "\n";
	if (stCal.span() < 200)
		std::cout << "warning: the 1st-99th percentiles span only " << fmt(stCal.span(), 1)
				  << " grey levels: the invariant's tails are heavy here; raise --min-span (or --tail) for more\n";
	return stCal;
}

/** OUT.ini: an [invariant] section, with where its values came from. */
std::string iniText(
	const InvariantParams& p, const TAlphaCurve* chosen, const TCalibrationInput& in, size_t images, double clipped,
	const TSuitabilityVerdict& verdict)
{
	shadyloc::CFilterInvariant filter;
	filter.setParams(p);
	std::ostringstream ini;
	if (chosen)
		ini << "# Calibrated by shadyloc calibrate-alpha (" << chosen->method << " method, " << chosen->items
			<< itemsOf(chosen->method) << ", 95% interval of alpha [" << fmt(chosen->ciLow) << ", "
			<< fmt(chosen->ciHigh) << "]).\n";
	else
		ini << "# alpha and beta given (--alpha); 8-bit mapping calibrated by shadyloc calibrate-alpha from "
			<< images << " images.\n";
	ini << "# Input linearisation: " << toString(in.linearisation)
		<< ". Clipping over the calibration images: " << fmt(100 * clipped, 2) << " %.\n"
		<< "# Suitability verdict: " << toString(verdict.verdict);
	for (const auto& r : verdict.reasons) ini << (&r == &verdict.reasons.front() ? " (" : ", ") << r.code;
	ini << (verdict.reasons.empty() ? "" : ")")
		<< (verdict.verdict == Suitability::Suitable ? ".\n" : ": not a confident calibration.\n")
		<< "# The 8-bit mapping (scale, offset, knees, tail slopes) defines the descriptors: keep it equal for map "
		   "and live data.\n"
		<< "[invariant]\n"
		<< filter.optionsAsIni();
	return ini.str();
}

/** OUT_curve.csv: alpha, then each method's cost (the curves share one grid). */
std::string curvesCsv(const std::vector<TAlphaCurve>& curves)
{
	std::ostringstream csv;
	csv << "alpha";
	for (const auto& c : curves) csv << "," << c.method;
	csv << "\n" << std::setprecision(8);
	for (size_t j = 0; j < curves.front().alpha.size(); j++)
	{
		csv << curves.front().alpha[j];
		for (const auto& c : curves) csv << "," << c.cost[j];
		csv << "\n";
	}
	return csv.str();
}

int run(int argc, char** argv)
{
	shadyloc::apps::CommandLine cli(
		"Calibrates the illumination-invariant transform of a camera from data: alpha (with beta = 1 - alpha), "
		"from shadow/no-shadow pairs, from same-view pairs under different light, from two runs of one route under "
		"different light, or unsupervised from ordinary "
		"images/a rawlog (entropy minimisation); then the 8-bit mapping (scale, offset). Writes OUT.ini (an "
		"[invariant] section for config/filters.ini), OUT_curve.csv and OUT_curve.png. Says whether the images suit the "
		"invariant channel (JPEG block grid, chroma subsampling, clipping, estimates at a search bound or apart): last "
		"line 'verdict: suitable|doubtful|unsuitable', exit status 0, 3 or 4 (docs/calibration.md).");
	auto& cmd = cli.cmd();
	TCLAP::ValueArg<std::string> pairsDir(
		"", "pairs", "directory of <name>_free.<ext> / <name>_shadow*.<ext> pairs of one view", false, "", "dir", cmd);
	TCLAP::MultiArg<std::string> pair("", "pair", "one shadow pair FREE,SHADOW (repeatable)", false, "free,shadow", cmd);
	TCLAP::MultiArg<std::string> sameView(
		"", "same-view", "two pixel-aligned images of one view under different light A,B (repeatable)", false, "a,b",
		cmd);
	TCLAP::MultiArg<std::string> runs(
		"", "runs",
		"two rawlogs of the same places under different light A,B (repeatable): every --every-th frame of A is "
		"matched to the frame of B that shares the most features, no poses needed",
		false, "a,b", cmd);
	TCLAP::MultiArg<std::string> images("", "image", "an ordinary image (repeatable; entropy method)", false, "file", cmd);
	TCLAP::ValueArg<std::string> imagesDir("", "images", "a directory of ordinary images (entropy method)", false, "", "dir", cmd);
	TCLAP::MultiArg<std::string> rawlog(
		"", "rawlog", "a rawlog; left/colour images (repeatable; entropy and edges methods)", false, "file", cmd);
	TCLAP::ValueArg<std::string> sensor("", "sensor", "only this sensor label of --rawlog", false, "", "label", cmd);
	shadyloc::apps::NumberArg<int> maxFrames(
		cli, "", "max-frames", "at most this many frames of each rawlog (0 = all)", 200, "n", 0, 1000000000);
	shadyloc::apps::NumberArg<int> every(
		cli, "", "every", "use every n-th rawlog frame", 1, "n", 1, 1000000);
	std::vector<std::string> methods{"auto", "pairs", "same-view", "runs", "edges", "entropy"};
	TCLAP::ValuesConstraint<std::string> methodC(methods);
	TCLAP::ValueArg<std::string> method(
		"", "method", "which estimate goes into OUT.ini (auto: pairs, else same-view, else runs, else edges)", false, "auto",
		&methodC, cmd);
	TCLAP::ValueArg<std::string> lin(
		"", "linearise", "REQUIRED: the camera's transfer curve, none|srgb|gamma (an input, not estimated)", true, "",
		"mode", cmd);
	shadyloc::apps::NumberArg<double> gamma(
		cli, "", "gamma", "exponent for --linearise gamma", 2.2, "g", 0.1, 10.0);
	TCLAP::ValueArg<std::string> order("", "channel-order", "memory order of the images (files: bgr)", false, "bgr", "bgr|rgb", cmd);
	shadyloc::apps::NumberArg<int> minCode(
		cli, "", "min-code", "skip pixels with a channel below this code (dark)", 8, "v", 0, 255);
	shadyloc::apps::NumberArg<int> maxCode(
		cli, "", "max-code", "skip pixels with a channel at/above this code (saturated)", 250, "v", 1, 256);
	shadyloc::apps::NumberArg<double> skipTop(
		cli, "", "skip-top", "fraction of top rows to ignore (sky)", 0.0, "f", 0.0, 0.95);
	shadyloc::apps::NumberArg<int> edgeStep(
		cli, "", "edge-step", "edges method: pixels between the two sides of an edge (> chroma blur)", 4, "px", 1, 64);
	shadyloc::apps::NumberArg<double> edgeMaxChroma(
		cli, "", "edge-max-chroma", "edges method: skip steps whose chromaticity change exceeds this many times their "
		"brightness change (material edges)", 1.0, "r", 0.05, 1e6);
	shadyloc::apps::NumberArg<int> stride(
		cli, "", "stride", "sample every n-th pixel in x and y", 2, "n", 1, 64);
	shadyloc::apps::NumberArg<double> aMin(
		cli, "", "alpha-min", "search range, low end", 0.05, "a", 0.0, 1.0);
	shadyloc::apps::NumberArg<double> aMax(
		cli, "", "alpha-max", "search range, high end", 0.95, "a", 0.0, 1.0);
	shadyloc::apps::NumberArg<double> step(
		cli, "", "step", "grid step of alpha", 0.005, "s", 0.0001, 0.5);
	shadyloc::apps::NumberArg<int> boot(
		cli, "", "bootstrap", "bootstrap rounds over images for the interval (0 = none)", 200, "n", 0, 100000);
	shadyloc::apps::NumberArg<double> tail(
		cli, "", "tail", "share of pixels clipped at each end of the 8-bit mapping", 0.002, "q", 0.0, 0.0099);
	shadyloc::apps::NumberArg<double> minSpan(
		cli, "", "min-span",
		"grey levels the 1st-99th percentiles get at least; where a linear mapping gives fewer, the tails beyond "
		"them are compressed (0: always linear)",
		210.0, "levels", 0.0, 240.0);
	shadyloc::apps::NumberArg<double> knownAlpha(
		cli, "", "alpha", "a known alpha (e.g. a datasheet's): no estimate, only the 8-bit mapping is calibrated; no curve",
		0.5, "a", 0.0, 1.0);
	shadyloc::apps::NumberArg<double> knownBeta(
		cli, "", "beta", "with --alpha: beta when alpha + beta != 1 (default 1 - alpha)", 0.5, "b", 0.0, 1.0);
	TCLAP::SwitchArg noPlot("", "no-plot", "do not draw OUT_curve.png (no gnuplot needed)", cmd);
	TCLAP::ValueArg<std::string> out("o", "output", "output prefix: OUT.ini, OUT_curve.csv, OUT_curve.png", true, "", "OUT", cmd);
	if (const auto rc = cli.parse(argc, argv)) return *rc;
	if (gamma.isSet() && lin.getValue() != "gamma") return cli.usageError("--gamma is used only with --linearise gamma");

	TCalibrationInput in;
	in.linearisation = parseLinearisation(lin.getValue());
	in.gamma = gamma.getValue();
	in.order = parseChannelOrder(order.getValue());
	in.minCode = minCode.getValue();
	in.maxCode = maxCode.getValue();
	in.skipTopFraction = skipTop.getValue();
	in.stride = stride.getValue();
	in.validate();
	TAlphaSearch search;
	search.alphaMin = aMin.getValue();
	search.alphaMax = aMax.getValue();
	search.step = step.getValue();
	search.bootstrapRounds = boot.getValue();
	search.validate();
	if (every.getValue() < 1) throw std::invalid_argument("--every must be >= 1");
	if (knownBeta.isSet() && !knownAlpha.isSet()) throw std::invalid_argument("--beta needs --alpha");
	if (knownAlpha.isSet() && method.isSet())
		throw std::invalid_argument("--method and --alpha exclude each other: --alpha gives alpha, no method estimates it");
	const fs::path outDir = fs::path(out.getValue()).parent_path();
	if (!outDir.empty() && !fs::is_directory(outDir))
		throw std::runtime_error("-o '" + out.getValue() + "': directory '" + outDir.string() + "' does not exist");
	shadyloc::io::OutputTransaction outputs;
	declareInputs(
		outputs, pairsDir.isSet() ? pairsDir.getValue() : "", imagesDir.isSet() ? imagesDir.getValue() : "",
		{{"--pair", pair.getValue()},
		 {"--same-view", sameView.getValue()},
		 {"--runs", runs.getValue()},
		 {"--image", images.getValue()},
		 {"--rawlog", rawlog.getValue()}});
	const bool withCurve = !knownAlpha.isSet();
	const std::string iniPath = out.getValue() + ".ini", csvPath = out.getValue() + "_curve.csv",
					  pngPath = out.getValue() + "_curve.png";
	const std::string iniTmp = outputs.addFile(iniPath, "-o (ini)");
	const std::string csvTmp = withCurve ? outputs.addFile(csvPath, "-o (curve csv)") : "";
	const std::string pngTmp = withCurve && !noPlot.getValue() ? outputs.addFile(pngPath, "-o (curve png)") : "";

	const TInputArgs inputArgs{
		pairsDir.isSet() ? pairsDir.getValue() : "", pair.getValue(), sameView.getValue(), runs.getValue(),
		images.getValue(), imagesDir.isSet() ? imagesDir.getValue() : "", rawlog.getValue(), sensor.getValue(),
		maxFrames.getValue(), every.getValue()};
	const TInputs data = readInputs(inputArgs, in);
	std::cout << "input: linearisation " << toString(in.linearisation)
			  << (in.linearisation == Linearisation::Gamma ? " (gamma " + fmt(in.gamma, 2) + ")" : "")
			  << ", channel order " << toString(in.order) << "; " << data.shadowPairs.size() << " shadow pair(s), "
			  << data.viewPairs.size() << " same-view pair(s), " << data.plain.size() << " ordinary image(s)\n";
	const std::vector<cv::Mat> all = data.allImages();

	// ---- estimates (none with a known alpha)
	std::vector<TAlphaCurve> curves;
	const TAlphaCurve* chosen = nullptr;
	InvariantParams p;
	if (knownAlpha.isSet())
	{
		p = in.params(knownAlpha.getValue());
		if (knownBeta.isSet()) p.beta = knownBeta.getValue();
		std::cout << "\nalpha given: " << fmt(p.alpha) << ", beta " << fmt(p.beta) << " (no estimate)\n";
	}
	else
	{
		curves = estimateCurves(data, all, in, search, edgeStep.getValue(), edgeMaxChroma.getValue());
		chosen = chooseCurve(curves, method.getValue());
		printEstimates(curves, chosen, search);
		p = in.params(chosen->best);
	}

	// ---- suitability
	const TSuitabilityVerdict verdict = judgeInputs(inputArgs, data, all, in, p, curves, chosen, search);
	printSuitability(verdict);

	// ---- mapping
	const InvariantParams pDefault = p;	 // the default mapping at the same alpha and beta
	p = calibrateMapping(all, p, tail.getValue(), in.stride, minSpan.getValue());
	const auto stCal = reportMapping(all, p, pDefault, in, minSpan.getValue(), verdict.verdict);

	// ---- outputs
	const std::string ini = iniText(p, chosen, in, all.size(), stCal.clipped(), verdict);
	writeText(iniTmp, ini);
	if (withCurve)
	{
		writeText(csvTmp, curvesCsv(curves));
		if (!pngTmp.empty())
			plotCurves(curves, csvTmp, pngTmp, 0.48,
				"alpha calibration (linearisation " + toString(in.linearisation) + ")");
	}
	outputs.commit();
	std::cout << "\nwrote " << iniPath << (withCurve ? ", " + csvPath : "")
			  << (withCurve && !noPlot.getValue() ? ", " + pngPath : "") << "\n\n" << ini;
	// Machine-readable: this last line, and the exit status (0 suitable, 3 doubtful, 4 unsuitable).
	std::cout << "\nverdict: " << toString(verdict.verdict) << "\n";
	return verdict.exitCode();
}
shadyloc::apps::RegisterCommand reg(
	"calibrate-alpha",
	{"alpha (beta = 1 - alpha) and the 8-bit mapping of the invariant from data (--pairs/--same-view/--images/--rawlog)",
	 run});
}  // namespace cmd_calibrate_alpha
