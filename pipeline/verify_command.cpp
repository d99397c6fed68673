// tolver verify as library functions, on one program and on a jobs file: see pipeline/verify.h.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <mutex>

#include "core/numerics/units.h"
#include "io/common/io_error.h"
#include "io/common/text_util.h"
#include "io/program/jobs_file.h"
#include "io/report/offscreen_display.h"
#include "pipeline/verify.h"

namespace tolver {

namespace fs = std::filesystem;

VerifyRun verifyPart(const VerifyInputs& in, const std::string& name_given,
                     const Progress& progress) {
  if (in.program.cl.empty() && in.program.nc.empty())
    throw FieldError("cl", "give the program (" + inputName("cl") + " or " + inputName("nc") +
                               ") or a jobs file (" + inputName("batch") + ")");
  if (in.machine.machine.empty()) throw FieldError("machine", "give the machine file");
  if (in.report_dir.empty()) throw FieldError("report_dir", "give the report directory");
  const std::string name =
      !name_given.empty()
          ? name_given
          : fs::path(in.program.cl.empty() ? in.program.nc : in.program.cl).stem().string();
  if (in.images) startDisplay();  // the X server starts while the part is swept
  VerifyRun run;
  run.verification = runVerification(in, name, [&](double f) {
    if (progress) progress("sweeping " + name, f);
  });
  run.report = writeVerification(*run.verification, in.report_dir, in.images, in.view3d, progress);
  run.verdict = run.verification->verdict;
  return run;
}

namespace {

JobOutcome outcomeOf(const std::string& name, const VerifyRun& run) {
  const Verification& v = *run.verification;
  const VerifyResult& result = v.result;
  JobOutcome out;
  out.name = name;
  out.verdict = run.verdict;
  out.verdict_text = toLower(verdictName(v.report));
  out.report = run.report;
  out.max_um = mmToUm(result.total_stats.max);
  out.min_um = mmToUm(result.total_stats.min);
  out.machine_rms_um = mmToUm(result.machine_stats.rms);
  out.percent_in = result.percent_in;
  out.regions = static_cast<int>(result.regions.size());
  return out;
}

}  // namespace

BatchRun verifyBatch(const VerifyInputs& base, const std::string& jobs_file,
                     const std::function<void(int, size_t, const JobOutcome&)>& done) {
  if (base.report_dir.empty()) throw FieldError("report_dir", "give the report directory");
  std::vector<VerifyInputs> jobs;
  std::vector<std::string> names;
  for (const VerifyJob& j : readJobsFile(jobs_file, base.tolerance_confirmed)) {
    VerifyInputs o = base;
    o.machine.machine = j.machine;
    o.machine.setup = j.setup;
    o.probed = j.probed;
    o.program.cl = j.cl;
    o.program.nc.clear();
    o.part = j.part;
    o.zones_file = j.zones;
    o.tolerance_mm = j.tolerance_mm;
    o.report_dir = (fs::path(base.report_dir) / j.name).string();
    jobs.push_back(o);
    names.push_back(j.name);
  }
  makeReportDir(base.report_dir);
  BatchRun run;
  run.jobs.resize(jobs.size());
  std::atomic<int> finished{0};
  std::mutex serial;
  tbb::parallel_for(size_t(0), jobs.size(), [&](size_t k) {
    JobOutcome& out = run.jobs[k];
    try {
      out = outcomeOf(names[k], verifyPart(jobs[k], names[k]));
    } catch (const InputError& e) {
      out.name = names[k];
      out.verdict = Verdict::BadInput;
      out.verdict_text = "error";
      out.error = e.what();
    } catch (const std::exception& e) {
      out.name = names[k];
      out.verdict = Verdict::BadInput;
      out.verdict_text = "error";
      out.error = std::string("internal error: ") + e.what();
    }
    std::lock_guard<std::mutex> lock(serial);
    const int n = ++finished;
    if (done) done(n, jobs.size(), out);
  });
  std::string csv =
      "name,verdict,min_um,max_um,machine_rms_um,percent_in_tolerance,regions,report,error\n";
  for (const JobOutcome& r : run.jobs) {
    run.verdict = worse(run.verdict, r.verdict);
    csv +=
        csvLine({r.name, r.verdict_text, formatWith("%.3f", r.min_um), formatWith("%.3f", r.max_um),
                 formatWith("%.3f", r.machine_rms_um), formatWith("%.3f", r.percent_in),
                 std::to_string(r.regions), r.report, r.error}) +
        "\n";
  }
  run.summary = (fs::path(base.report_dir) / "summary.csv").string();
  writeFileAtomically(run.summary, csv);
  return run;
}

}  // namespace tolver
