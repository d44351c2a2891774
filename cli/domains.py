"""`tailor domains`: the installed simulators and the bundled domains, and what each can do."""

from __future__ import annotations

import argparse
import json
import sys



def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paths", nargs="*", metavar="DIR", help="also describe these domain folders")
    parser.add_argument("--json", action="store_true", help="print the listing as JSON")


def describe(domain_dir) -> dict:
    """What the domain in `domain_dir` provides: problems, binding, simulator, models (those `tailor refine` would
    read, model_store.resolve_models), recipe, evaluation."""
    from tailor.errors import TailorError
    from tailor.refinement.binding import BINDING_FILE, DOMAIN_FILE, load_domain_binding
    from tailor.refinement.binding_domain import read_vocabulary
    from tailor.refinement.learning.recipe import recipe_from_binding
    from tailor.refinement.model_store import resolve_models

    problems = sorted(p.stem for p in (domain_dir / "problems").glob("*.pddl"))
    vocabulary = read_vocabulary(domain_dir / DOMAIN_FILE)  # the PDDL domain's own name (None: unreadable)
    info = {"name": vocabulary.name if vocabulary is not None and vocabulary.name else domain_dir.name,
            "folder": domain_dir.name, "path": str(domain_dir), "problems": problems, "simulator": None,
            "can": ["plan"], "models": [], "notes": []}
    if not (domain_dir / BINDING_FILE).is_file():
        info["notes"].append(f"no {BINDING_FILE}: planning only")
        return info
    try:
        binding = load_domain_binding(domain_dir, vocabulary=vocabulary)  # (the domain file read once)
    except TailorError as exc:
        info["notes"].append(str(exc))
        return info
    info["simulator"] = binding.simulator
    try:  # the models `tailor refine` would read: also those training wrote to the user data folder
        source = resolve_models(domain_dir)
    except TailorError as exc:
        info["notes"].append(str(exc))
    else:
        info["models"] = sorted(p.name for p in source.path.glob("*.json"))
        info["models_folder"] = str(source.path)
    for capability, check in (("train", lambda: recipe_from_binding(binding, domain_dir)),
                              ("evaluate", binding.require_evaluation)):
        try:
            check()
            info["can"].append(capability)
        except TailorError as exc:
            info["notes"].append(str(exc) if exc.file else f"{domain_dir / BINDING_FILE}: {exc.message}")
    if "train" in info["can"]:
        info["can"].insert(info["can"].index("train") + 1, "gather")
    if info["models"] and binding.entry.team is not None:
        info["can"].append("coordinate")
    if info["models"]:
        info["can"].insert(1, "refine")
    else:
        info["notes"].append("no models yet: run `tailor train` first")
    return info


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from tailor.planner_bridge import resolve_domain_dir
    from tailor.planner_bridge.bundled import DOMAINS_DIR, bundled_domains
    from tailor.sims import registry

    sims = [{"name": e.name, "actions": list(e.actions), "scenarios": list(e.scenarios),
             "situations": list(e.situations), "description": e.description}
            for e in registry.simulators().values()]
    domains = [describe(DOMAINS_DIR / name) for name in bundled_domains()]
    domains += [describe(Path(resolve_domain_dir(p))) for p in args.paths]
    if args.json:
        from tailor.outputs import provenance, versioned

        sys.stdout.write(json.dumps(versioned("domains", {"simulators": sims, "failed_simulators": registry.failed(),
                                                          "domains": domains}, provenance(getattr(args, "argv", None))),
                                    indent=1) + "\n")
        return 0
    out = sys.stdout.write
    out("Simulators (entry point group tailor.simulators):\n")
    for s in sims:
        out(f"  {s['name']:<10} actions {', '.join(s['actions'])}; scenarios {', '.join(s['scenarios']) or '-'}; "
            f"situations {', '.join(s['situations']) or '-'}\n             {s['description']}\n")
    for name, why in registry.failed().items():
        out(f"  {name:<10} could not be loaded: {why}\n")
    out("\nDomains:\n")
    width = max((len(" ".join(d["can"])) for d in domains), default=0)
    for d in domains:
        folder = "" if d["folder"] == d["name"] else f" (folder {d['path']})"
        out(f"  {d['name']:<10} {' '.join(d['can']):<{width}}  simulator {d['simulator'] or '-'}; "
            f"problems {', '.join(d['problems'])}{folder}\n")
        for note in d["notes"]:
            out(f"             note: {note}\n")
    return 0
