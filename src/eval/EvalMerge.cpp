/* ShadyLoc — the leave-one-out evaluation's merge: collect the jobs' records,
 * make the tables, write one output each (MergeTables.h), and publish them
 * with the pairs' files and Figures 7-9 as a whole (docs/evaluation.md).
 * Deterministic: the same job records give the same bytes, whichever way
 * the jobs ran. */
#include <shadyloc/eval/Figures.h>
#include <shadyloc/eval/LeaveOneOut.h>
#include <shadyloc/io/OutputTransaction.h>

#include "MergeTables.h"

#include <filesystem>
#include <fstream>
#include <utility>

namespace shadyloc::eval
{
namespace fs = std::filesystem;

namespace
{
using TOutputs = std::vector<std::pair<std::string, std::string>>;	//!< (file name, text)

/** Every pair's published files into the transaction's pairs folder. */
void copyPairs(const TMerged& m, const fs::path& pairsTmp)
{
	for (const auto& j : m.jobs)
	{
		if (j.isMap) continue;
		const fs::path d = pairsTmp / pairDirName(j, m.runs());
		fs::create_directory(d);
		for (const char* f : kPairFiles) fs::copy_file(fs::path(m.outDir) / "jobs" / j.name / f, d / f);
	}
}

/** Figures 7-9 from the pairs' frames.csv (docs/figures.md): Figure 7 per
 * (live, map), Figure 8 per live run, Figure 9 from the pooled episodes of
 * eval.json, so the figure and the JSON agree. */
void drawFigures(const TMerged& m, const fs::path& pairsTmp, const fs::path& figTmp)
{
	const auto& runs = m.runs();
	const size_t n = runs.size();
	for (size_t i = 0; i < n; i++)
	{
		std::vector<TFigurePair> maps;
		for (size_t k = 0; k < n; k++)
		{
			if (k == i) continue;
			const auto csvOf = [&](EvalSystem s) {
				return (pairsTmp / pairDirName(m.pairJob(i, k, s), runs) / "frames.csv").string();
			};
			maps.push_back({runs[k].name, csvOf(EvalSystem::Baseline), csvOf(EvalSystem::Combined)});
			figure7(runs[i].name, runs[k].name, maps.back().baselineCsv, maps.back().combinedCsv,
					(figTmp / ("figure7_" + runs[i].name + "__" + runs[k].name + ".png")).string());
		}
		figure8(runs[i].name, maps, (figTmp / ("figure8_" + runs[i].name + ".png")).string());
	}
	figure9(m.pooled[0].between, m.pooled[1].between, (figTmp / "figure9.png").string(),
			m.anyGt() ? "ground truth" : "VO", m.evo.blind_long_m);
}

/** The outputs, OUTDIR/pairs and OUTDIR/figures, all committed together or none. */
void publish(const TMerged& m, const TOutputs& outputs)
{
	const fs::path out(m.outDir);
	io::OutputTransaction tx;
	tx.setMinLoggingLevel(mrpt::system::LVL_ERROR);
	tx.addInput((out / "jobs").string(), "job outputs");
	tx.addInput(m.in.runsPath, "run list");
	for (const auto& [name, text] : outputs)
	{
		const std::string tmp = tx.addFile((out / name).string(), name);
		std::ofstream f(tmp, std::ios::binary);
		f << text;
		f.close();
		if (!f) throw std::runtime_error("cannot write '" + tmp + "'");
	}
	const fs::path pairsTmp = tx.addDirectory((out / "pairs").string(), "pairs", "shadyloc eval pairs folder");
	copyPairs(m, pairsTmp);
	const fs::path figTmp = tx.addDirectory((out / "figures").string(), "figures", "shadyloc eval figures folder");
	drawFigures(m, pairsTmp, figTmp);
	tx.commit();
}
}  // namespace

TMergeResult merge(const std::string& outDir, const TEvalInputs& in, const std::vector<TEvalJob>& jobs, double wall_s)
{
	TMerged m(outDir, in, jobs);
	collectRecords(m);
	makeTables(m);
	const TOutputs outputs = {
		{"table1.md", table1Markdown(m)},
		{"table1.csv", table1Csv(m)},
		{"summary.md", summaryMarkdown(m)},
		{"eval.json", evalJson(m)},
		{"timing.json", evalTimingJson(m, wall_s)},	 // apart: the results compare byte for byte
		{"figures_inputs.tsv", figuresInputs(m)},  // for redrawing the figures with `shadyloc figures`
	};
	publish(m, outputs);
	return {outputs[0].second, outputs[2].second};
}

}  // namespace shadyloc::eval
