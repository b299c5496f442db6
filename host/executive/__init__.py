"""Layer 2 of the mission stack (paper 001 §II-B, §III-B): the executive.

Each mission action is refined into a behaviour tree (py_trees) from its recipe (``trees``): a
reactive sequence per skill whose guard is re-checked on every tick and *holds* the tree while
layer 0 repairs what the skill needs, local recovery by bounded retry and fallbacks, and the
skills as leaves (``nodes``). ``runner.Executive`` ticks the tree, keeps its trace (``TreeChange``
events) and reports ⟨s, Δ⟩ up with the failed subtask and its explanation.
"""

from host.executive.nodes import Guard, SkillAction, Trace
from host.executive.runner import Executive
from host.executive.trees import Recipe, RecipeError, RecipeStep, build, parse_recipe

__all__ = ["Executive", "Guard", "Recipe", "RecipeError", "RecipeStep", "SkillAction", "Trace",
           "build", "parse_recipe"]
