"""The markdown report (docs/REPRODUCTION.md) and its tables."""

from __future__ import annotations

import os
import subprocess

import numpy as np

from experiments.harness.markdown import mean_sd, table
from experiments.harness.study import SCALES
from experiments.harness.loading import read_json
from imrl_jax.analysis.relive import CHILDHOOD_DRAWN_STEPS, CHILDHOOD_TAIL, DRAWN_STEPS, FRESH_LIVES, PATH_STEPS
from imrl_jax.analysis.claims import CLAIMS, EVOLVED, LAST_GENERATIONS, PAPER, PLATEAU_FRACTION, RULES, SEEN, _fmt
from imrl_jax import conditions

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def figures_of(document: str) -> str:
    """The folder of a report's figures and summaries: beside it, named after it (docs/reproduction_cpu)."""
    return os.path.join(os.path.dirname(document), os.path.splitext(os.path.basename(document))[0].lower())


def report_name(scale: str) -> str:
    """The report of a scale: the paper scale's is REPRODUCTION.md, others are labelled (REPRODUCTION_CPU.md)."""
    return "REPRODUCTION.md" if scale == "paper" else f"REPRODUCTION_{scale.upper()}.md"


def other_scale_section(doc_dir: str) -> list[str]:
    """A labelled section on each reduced scale's report found beside the paper scale's: its verdicts, a link."""
    out = []
    for other in [s for s in SCALES if s != "paper"]:
        doc = report_name(other)
        claims = read_json(os.path.join(doc_dir, os.path.basename(figures_of(doc)), "claims.json"))
        if claims is None or not os.path.isfile(os.path.join(doc_dir, doc)):
            continue
        variants = list(next(iter(claims["claims"].values()))["variants"])
        out += ["", f"## The same claims at the {other} scale", "",
                f"**Another run, at the {claims.get('scale_label', other + ' scale')}.** Its figures, numbers and "
                f"discussion are in [{doc}]({doc}); only its verdicts are repeated here.", "",
                table(["#", "claim", *variants],
                      [[n, c["text"], *(f"{c['variants'][v]['verdict']} ({c['variants'][v]['measured']})"
                                        for v in variants)] for n, c in claims["claims"].items()])]
    return out


def scale_label(manifest: dict) -> str:
    """The sizes the numbers were measured at, in one short line (every table and figure names it)."""
    sizes = manifest["sizes"]
    return (f"{manifest['scale']} scale: {sizes['seeds']:,} seeds x {sizes['generations']:,} generations, lives of "
            f"{sizes['childhood_steps']:,} + 6 x {sizes['task_steps']:,} steps, learning tests of "
            f"{sizes['test_steps']:,} cycles per task")


def sizes_table(data: dict) -> str:
    """The run's sizes beside the paper's, with the fraction of the paper's where they differ."""
    sizes, paper = data["manifest"]["sizes"], SCALES["paper"]
    config = next((run["config"] for run in data["evolutions"].values() if run.get("config")), {})
    # the population as the evolutions ran it (none finished yet: the scale's, if it names one)
    population = (config.get("population_size", sizes.get("population")),
                  config.get("num_parents", sizes.get("parents")))
    body = [[name, f"{sizes[key]:,}" + _fraction(sizes[key] / paper[key]), f"{paper[key]:,}"] for name, key in (
        ("seeds (runs)", "seeds"), ("generations", "generations"), ("childhood steps", "childhood_steps"),
        ("steps per adult task (6 tasks)", "task_steps"), ("learning test: best individuals per run", "best"),
        ("learning test: tests per individual", "tests"), ("learning test: cycles per task", "test_steps"),
        ("steady state: last cycles", "steady_steps"))]
    body.insert(2, ["population, parents", ", ".join("?" if v is None else f"{v:,}" for v in population), "50, 10"])
    return table(["", f"this run ({data['manifest']['scale']} scale)", "paper"], body)


def _fraction(ratio: float) -> str:
    """After a size that differs from the paper's, its fraction of the paper's: " (1/5)", " (x0.4)"."""
    inverse = 1 / ratio
    if ratio == 1:
        return ""
    return f" (1/{inverse:g})" if ratio < 1 and abs(inverse - round(inverse)) < 1e-9 else f" (x{ratio:.3g})"


#: What each variant of the learning rules is, for the report's header.
VARIANT_TEXT = {
    "paper": "`paper`: the learning rules as written",
    "extension": "`extension`: MODEL.md's learning extensions at the `extension` preset",
    "skills": "`skills`: the paper's rules in childhood with a respawning wall and fast-starting experts, the "
              "extension's selector in adulthood (docs/CHILDHOOD.md)",
    "faithful": "`faithful`: the learning rules as written but for the extension's selector in adulthood, SLE's "
                "noise annealed over the whole test (the reading that reproduces the most of Fig. 3: docs/CLAIMS.md)",
}


def pipeline_command(study: str) -> str:
    """The command that (re)makes a study's runs (the make target of the two committed scales)."""
    command = f"python -m experiments run {study}"
    target = {"reproduction": "make reproduce", "reproduction-cpu": "make reproduce-cpu"}.get(study)
    return f"`{target}` (`{command}`)" if target else f"`{command}`"


def sharers(data: dict, variant: str, condition: str) -> list[str]:
    """The variants whose run of a condition is ``variant``'s (faithful's EE-LS: skills and faithful)."""
    return [v for v in data["variants"] if data["owners"].get((v, condition)) == variant]


def specialisation_rows(lives: dict) -> list[dict]:
    """One row per expert of each best individual and phase (adult tasks; LE-LS also the end of childhood)."""
    rows = []
    for (variant, condition), life in lives.items():
        followed = [SEEN[int(c)] if c >= 0 else "" for c in life["probe"].followed]
        phases = [("adult tasks", life["shares"], life["steps"])]
        if life.get("childhood_shares") is not None:
            phases.append((f"childhood, last {CHILDHOOD_TAIL:.0%}", life["childhood_shares"], life["childhood_steps"]))
        for phase, shares, steps in phases:
            total = max(int(np.sum(steps)), 1)
            rows += [dict(variant=variant if conditions.get(condition).learns else "both", condition=condition,
                          phase=phase, seed=life["seed"], generation=life["generation"], expert=e + 1, steps=int(n),
                          control_share=round(int(n) / total, 4),
                          **{name: None if not np.isfinite(v) else round(float(v), 4) for name, v in zip(SEEN, row)},
                          follows=followed[e]) for e, (row, n) in enumerate(zip(shares, steps))]
    return rows


def write_document(path: str, figures: str, data: dict, numbers: dict, lives: dict, spec_rows: list[dict],
                   written: dict, baselines: dict | None = None, study: str = "reproduction") -> None:
    """The markdown report (with a section on the brax baselines when ``baselines`` has any)."""
    from imrl_jax.runs.checkpoint import git_commit

    manifest, results, owners, variants = data["manifest"], data["results"], data["owners"], data["variants"]
    label, scale, doc_dir = scale_label(manifest), manifest["scale"], os.path.dirname(os.path.abspath(path))
    rel = lambda name: os.path.relpath(os.path.join(figures, name), doc_dir)  # noqa: E731
    panels = lambda key: [text for v in variants if v in written[key]  # noqa: E731  (a figure per variant: Fig. 3a)
                          for text in ("", f"**{v}**", "", f"![Fig. {key[3:]}, {v}]({rel(written[key][v])})")]
    out = ["# Reproduction of Schembri, Mirolli & Baldassarre (2007): Fig. 3 and the seven claims"
           + ("" if scale == "paper" else f", at the {scale} scale (reduced)"), ""]
    inside = os.path.abspath(results).startswith(ROOT + os.sep)
    out += [f"Written by `experiments/report.py` from `{os.path.relpath(results, ROOT) if inside else results}`. "
            f"**All numbers below are at the {label}.**", "", sizes_table(data)]
    if scale != "paper":
        out += ["", "This is a **reduced-scale** reproduction: fewer seeds and generations and shorter lives and "
                    "learning tests than the paper's (10 seeds, 100 generations, 150,000 childhood steps, 100,000 "
                    "steps per task, tests of 10 best x 10 tests x 1,000,000 cycles). Its numbers are not the "
                    "paper's numbers; the claims are judged on the shapes and orders the paper reports."
                + (" The paper-scale run is reported in [REPRODUCTION.md](REPRODUCTION.md)."
                   if os.path.isfile(os.path.join(doc_dir, "REPRODUCTION.md")) and
                   os.path.basename(path) != "REPRODUCTION.md" else "")]
    commits = sorted({c for c in [run.get("git_commit") for run in data["evolutions"].values()]
                      + [t["steady"].get("git_commit") for t in data["tests"].values()] if c})
    about = "; ".join(VARIANT_TEXT.get(v, f"`{v}`: a row of docs/CLAIMS.md") for v in variants)
    out += ["", f"- Command: {pipeline_command(study)}",
            f"- Results made at commit `{manifest.get('git_commit', 'unknown')}`"
            + (f" (stages ran at {', '.join(f'`{c[:10]}`' for c in commits)})" if len(commits) > 1 else ""),
            f"- Report written at commit `{git_commit()}`" + (" (with uncommitted changes)" if _dirty() else ""),
            f"- Variants: {', '.join(variants)} ({about}). EE-ES learns nothing, so its one evolution serves every "
            f"variant" + "".join(f"; {v}'s {c} is the {owners[v, c]} run (the same rules for it)" for v in variants
                                 for c in EVOLVED if conditions.get(c).learns and owners.get((v, c), v) != v) + "."]
    if data["missing"]:
        out += ["", f"**Unfinished run: {len(data['missing'])} stage(s) not done yet** "
                    f"({', '.join(data['missing'])}). What they would measure is shown as not available; run the "
                    f"command again to go on."]
    if manifest.get("stages"):
        out += ["", "<details><summary>Stages (commands and seconds)</summary>", "",
                table(["stage", "command", "seconds"],
                      [[name, f"`{s['command']}`", s.get("seconds", "")] for name, s in manifest["stages"].items()]),
                "", "</details>"]

    out += ["", "## The arena and the tasks (Fig. 1)", "", f"![arena and tasks]({rel(written['arena'])})"]
    if written["fig3"]:
        out += ["", "## Fig. 3 in the paper's layout", "",
                "The paper's three panels side by side for each variant: (a) the best fitness per generation of "
                "the evolved conditions, (b) the learning tests of the conditions that learn (LE-LS, EE-LS, SLE; "
                "EE-ES learns nothing and appears in (c) only, as in the paper), (c) the steady state of all four "
                f"(dark: mean over runs, +-1 sd; light: the best run). The sections below show each panel with "
                f"its numbers ({label})."] + panels("fig3")

    out += ["", "## Fig. 3a: evolution of the best fitness", "",
            f"Best fitness per generation, mean over seeds with a band of +-1 sd ({label})."] + panels("fig3a")
    rows, expected = [], manifest["sizes"]["generations"]
    for variant in variants:
        for condition, e in numbers[variant]["evolution"].items():
            life = lives.get((owners[variant, condition], condition))
            rows.append([variant, condition, mean_sd(e["final_best_mean"], e["final_best_sd"]),
                         ", ".join(f"{v:.3f}" for v in e["final_best_per_seed"]), _fmt(e["plateau_generation"]),
                         e["generations"] if e["generations"] == expected else f"{e['generations']} of {expected}",
                         "-" if life is None else f"seed {life['seed']}, gen {life['generation']}: "
                                                  f"{life['fitness']:.3f} (relived {life['relived_fitness']:.3f})",
                         "-" if life is None else
                         f"{np.mean(life['fresh']['mean']):.3f} (seeds {np.min(life['fresh']['mean']):.3f}-"
                         f"{np.max(life['fresh']['mean']):.3f}; sd of a genome's lives "
                         f"{np.mean(life['fresh']['sd']):.3f})"])
    out += ["", f"Final best fitness = mean of each seed's last {LAST_GENERATIONS} generations; mean +- sd over "
                f"seeds. Plateau = first generation at {PLATEAU_FRACTION:.0%} of the final value of the mean curve. "
                f"({label})", "",
            table(["variant", "condition", "final best fitness", "per seed", "plateau generation", "generations",
                   "best individual (fitness)", f"fresh lives of each seed's best ({FRESH_LIVES} each)"], rows)]
    if lives:
        out += ["", "\"Final best fitness\" is the recorded best of each generation: the best of its 50 noisy lives, "
                    "as in the paper's Fig. 3a; claims 1 to 4 use it. \"Relived\": the best individual lives its "
                    "evaluated life again with the same keys; it equals the recorded fitness (the same life: same "
                    "keys, same program), so it shows that the life is reproducible, not how good the genome is. "
                    f"\"Fresh lives\": each seed's best genome of the last generation lives {FRESH_LIVES} lives with "
                    "keys the GA never used; their mean over seeds (the range of the seeds' means; the mean sd of "
                    "one genome's lives) is what the genomes score, below the recorded best because the best of a "
                    "generation's lives is partly the luckiest."]

    out += ["", "## Fig. 3b: learning tests", "",
            f"Performance per bin (reaches / the bin's theoretical maximum), mean over all tests and tasks, band "
            f"+-1 sd over runs ({label}). LE-LS tests start with a fresh childhood; EE-ES does not learn; SLE "
            f"learns from scratch."] + panels("fig3b")

    out += ["", "## Fig. 3c: steady state", ""] + ([f"![Fig. 3c]({rel(written['fig3c'])})", ""]
                                                  if written.get("fig3c") else [])
    out += [f"Steady state = mean performance over the last cycles of each test (see the scale); mean +- sd over "
            f"runs, best run, per task (mean over runs). ({label})", "",
            table(["variant", "condition", "steady state (mean +- sd over runs)", "best run", "per task 1-6",
                   "whole test", "runs x best x tests"],
                  [[v, c, mean_sd(t["steady_mean"], t["steady_sd"]), f"{t['steady_best_run']:.3f} (run "
                    f"{t['best_run']})", ", ".join(f"{x:.2f}" for x in t["steady_per_task"]),
                    f"{t['whole_test_mean']:.3f}", f"{t['num_runs']} x {t['num_best']} x {t['num_tests']}"]
                   for v in variants for c, t in numbers[v]["learning_tests"].items()])]

    out += ["", "## Behaviour of the best evolved individuals", "",
            f"The fittest individual of the last generation over all seeds of each evolution relives the life that "
            f"earned its fitness (\"relived\" above: the same keys), then drives each task for {PATH_STEPS:,} steps "
            f"from the weights it ended that task with (its selector still learning, as in adulthood). Drawn: the "
            f"last {DRAWN_STEPS} of them per task, coloured by the expert in control; for LE-LS also the last "
            f"{CHILDHOOD_DRAWN_STEPS:,} childhood steps. The bars show, per expert, the share of its control steps "
            f"on which the retina's central receptors see red, green, blue or nothing ({label}). The genomes are "
            f"kept in `best_genomes.npz` beside the results, so that these paths can be drawn again. (Evolutions run "
            f"by the pipeline now also commit their last population and newest checkpoint; those of this report's "
            f"runs were not kept by the machine that ran them, so only these 10 best per seed can be "
            f"relived, and extending the runs means running them again.)"]
    if not written["paths"]:
        out += ["", "(not drawn: no population or best_genomes.npz, or `--no-behaviour`)"]
    for (variant, condition), name in written["paths"].items():
        life = lives[variant, condition]
        header = (f"{condition} (every variant)" if not conditions.get(condition).learns else
                  f"{condition}, {' and '.join(sharers(data, variant, condition)) or variant}")
        out += ["", f"**{header}**: stereotypy (share of turns the same way) {_fmt(life['stereotypy'], 2)}, "
                    f"speed {_fmt(life['speed'], 2)} cm/step (at most {life['config'].max_speed:g}), most-used "
                    f"expert in control {life['dominant_expert']:.0%} of the steps", "",
                f"![paths {header}]({rel(name)})"]

    out += ["", "### Expert specialisation", "",
            f"*follows* is claim 7's definition: the colour each expert of the best individual takes at >= 75 % of "
            f"the junctions when it drives alone from fixed starts (`imrl_jax.analysis.behaviour.specialisation`, the "
            f"junction probe; \"-\": none). The other columns are what the retina's central receptors see on each "
            f"expert's control steps during the drawn paths (`colour_shares`): on this floor no colour runs "
            f"straight for long, so those shares stay mixed even for an expert that follows a colour, and they are "
            f"not the claim's measure. Also in `{os.path.basename(written['specialisation'])}`. ({label})", "",
            table(["variant", "condition", "phase", "expert", "control", *(f"sees {n}" for n in SEEN),
                   "follows (probe)"],
                  [[r["variant"], r["condition"], r["phase"], r["expert"], f"{r['control_share']:.0%}",
                    *(_fmt(r[name], 2) for name in SEEN), r["follows"] or "-"] for r in spec_rows])
            if spec_rows else "(no individual was simulated)"]

    out += ["", "## The seven claims", "", f"Measured at the {label}. The verdicts follow the rules below, "
                                           "computed by `experiments/report.py` (also in `claims.json`); claims "
                                           "1 to 4 judge finished evolutions only.", "",
            table(["#", "claim", "variant", "measured", "paper", "verdict"],
                  [[n, text if v == variants[0] else "", v, numbers[v]["claims"][n]["measured"], PAPER[n],
                    f"**{numbers[v]['claims'][n]['verdict']}**"] for n, text in CLAIMS.items() for v in variants]),
            "", "### Rules", ""] + [f"{n}. {rule}" for n, rule in RULES.items()]
    if baselines:
        out += baselines_section(baselines, data, written, rel, label)
    if scale == "paper":  # the reduced scales' verdicts, labelled; a reduced report only links the paper's (above)
        out += other_scale_section(doc_dir)
    discussion = os.path.join(results, "discussion.md")
    with open(discussion if os.path.isfile(discussion) else os.devnull) as f:
        out += ["", "## Discussion", "", f.read().strip() or "(no discussion written yet)"]
    os.makedirs(doc_dir, exist_ok=True)
    from imrl_jax.runs.rundir import write_atomic

    write_atomic(path, ("\n".join(out) + "\n").encode())


def baselines_section(baselines: dict, data: dict, written: dict, rel, label: str) -> list[str]:
    """Modern deep RL from brax.training on the same tasks, beside this report's learning tests."""
    from experiments.harness.figures import baseline_label

    out = ["", "## Modern deep RL baselines (brax.training)", "",
           "Each task learned from scratch by brax's PPO or ES on the arena's brax environments "
           "(`imrl_jax.agent.brax_env`), measured as the learning tests are: reaches / theoretical maximum, here of the "
           "trained policy acting (sampling its actions, as the paper's learners are measured while they act) "
           "from the task's start, replayed by the project's own step; the policy's mode in the last column. The "
           "baselines' own scale is their budget of cycles per task, not this report's: the paper's learning "
           "test gives 1,000,000. Made by `python -m experiments run baselines`; what, how and why in "
           "[BASELINES.md](BASELINES.md)."] + (["", f"![baselines]({rel(written['baselines'])})"]
                                               if written.get("baselines") else [])
    test_steps = max((int(t["steps"][-1]) for t in data["tests"].values()), default=None)
    # each baseline's curve at the tests' length, interpolated between its evaluations (None: it stopped before)
    same = {name: float(np.interp(test_steps, b["steps"], b["mean"])) if test_steps and test_steps <= b["steps"][-1]
            else None for name, b in baselines.items()}
    at_tests = lambda cell: [cell] if test_steps else []  # noqa: E731  (a column when tests are; cells made anyway)
    per_task = lambda values: ", ".join(f"{v:.2f}" for v in values)  # noqa: E731
    performance = lambda b: b["summary"]["performance_mean"]  # noqa: E731
    rows = [[baseline_label(b), mean_sd(performance(b), b["summary"]["performance_sd_over_seeds"]),
             per_task(b["per_task"]), *at_tests("-" if same[name] is None else f"{same[name]:.3f}"),
             f"{b['summary']['performance_deterministic_mean']:.3f}"] for name, b in baselines.items()]
    rows += [[f"{condition}, {variant} rules: steady state ({label.split(':')[0]})",
              mean_sd(t["steady"]["steady_mean"], t["steady"]["steady_sd"]), per_task(t["steady"]["steady_per_task"]),
              *at_tests(f"{t['steady']['steady_mean']:.3f}"), "-"] for (variant, condition), t in data["tests"].items()]
    out += ["", table(["learner", "performance (mean +- sd over seeds or runs)", "per task 1-6",
                       *at_tests(f"at {test_steps or 0:,} cycles (this report's test length; interpolated)"),
                       "deterministic (mode)"], rows)]
    best = max(baselines.values(), key=performance)
    lines = [f"Best baseline: {baseline_label(best)} at {performance(best):.3f}."]
    top = max((b for b in baselines.values() if b["summary"]["steps"] <= 1_100_000), key=performance, default=None)
    if top is not None:
        lines.append(f"With the paper's learning-test budget, {baseline_label(top)} reaches {performance(top):.3f}.")
    if data["tests"]:
        (variant, condition), t = max(data["tests"].items(), key=lambda item: item[1]["steady"]["steady_mean"])
        lines.append(f"The paper's architecture here ({label}): best steady state {condition} under the {variant} "
                     f"rules, {t['steady']['steady_mean']:.3f}.")
        name = max((name for name, value in same.items() if value is not None), key=same.get, default=None)
        if name is not None:
            lines.append(f"With the same experience as those tests ({test_steps:,} cycles per task), the best "
                         f"baseline is at {same[name]:.3f} ({baseline_label(baselines[name])}, interpolated between "
                         f"its evaluations).")
    sps = [f"{baseline_label(b).split(' (')[0]}: {b['summary']['steps_per_s_median']:,.0f}"
           for b in baselines.values() if b["summary"].get("steps_per_s_median")]
    out += ["", " ".join(lines)]
    if sps:
        out += ["", f"Training speed (median control cycles per second over runs, compilation and evaluation "
                    f"excluded): {'; '.join(sps)}."]
    return out


def _dirty() -> bool:
    """Whether the code that makes the report differs from its commit (the commit alone would not remake it)."""
    # only the package and the experiment scripts count: the report's own outputs and the results it reads are
    # tracked files too, and rewriting them must not flag the report
    try:
        out = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", "imrl_jax",
                              "experiments/*.py"], cwd=ROOT, capture_output=True, text=True, timeout=10)
        return bool(out.stdout.strip())
    except (OSError, subprocess.SubprocessError):
        return False
