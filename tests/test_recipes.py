"""Recipe loading: each kind of mistake gives one message naming file, line, field and plugin."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

import retarget
from retarget.errors import RecipeError
from retarget.recipe import load, parse_text, recipe_schema, resolve, write_lock
from retarget.registry import Registry
from retarget.registry.loader import load_plugins
from retarget.testing.fakes import TinyCharacter


class TinyPlugins:
    @retarget.hookimpl
    def register_characters(self, register) -> None:
        register(TinyCharacter)


@pytest.fixture(scope="module")
def registry() -> Registry:
    return load_plugins(strict=True, modules={"tiny_plugins": TinyPlugins()})


GOOD = """\
name: demo
character: tiny
rewards:
  action_diff: {weight: 0.2}
  smooth: {type: action_min, k: 0.3}
terminations:
  episode_cap: {max_steps: 100}
"""


def write(tmp_path: Path, text: str, name: str = "recipe.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def error_of(path: Path, registry: Registry, **kwargs) -> RecipeError:
    with pytest.raises(RecipeError) as info:
        load(path, registry, **kwargs)
    return info.value


def test_good_recipe_resolves_with_defaults_filled(tmp_path: Path, registry: Registry) -> None:
    resolved = load(write(tmp_path, GOOD), registry)
    data = resolved.to_dict()
    assert data["rewards"]["action_diff"] == {"type": "action_diff", "weight": 0.2, "k": 10.0}
    assert data["rewards"]["smooth"]["type"] == "action_min"
    assert resolved.component("terminations.episode_cap").config.max_steps == 100


def test_typo_field_names_file_line_field_plugin_and_suggests(
    tmp_path: Path, registry: Registry
) -> None:
    path = write(tmp_path, GOOD.replace("{weight: 0.2}", "{wieght: 0.2}"))
    err = error_of(path, registry)
    assert err.file == str(path) and err.line == 4
    assert err.field == "rewards.action_diff.wieght"
    assert "action_diff" in (err.plugin or "")
    assert "did you mean 'weight'" in (err.hint or "")
    assert str(path) in err.format() and "wieght" in err.format()


def test_typo_in_structure_suggests_close_field(tmp_path: Path, registry: Registry) -> None:
    err = error_of(write(tmp_path, GOOD.replace("rewards:", "reward:")), registry)
    assert err.field == "reward" and err.line == 3
    assert "did you mean 'rewards'" in (err.hint or "")


def test_wrong_type_names_field_and_value(tmp_path: Path, registry: Registry) -> None:
    err = error_of(write(tmp_path, GOOD.replace("max_steps: 100", "max_steps: lots")), registry)
    assert err.field == "terminations.episode_cap.max_steps" and err.line == 7
    assert "'lots'" in err.message


def test_unknown_plugin_lists_choices(tmp_path: Path, registry: Registry) -> None:
    err = error_of(write(tmp_path, GOOD.replace("type: action_min", "type: action_mni")), registry)
    assert err.field == "rewards.smooth.type" and err.line == 5
    assert "unknown reward 'action_mni'" in err.message
    assert "did you mean 'action_min'" in (err.hint or "")


def test_bad_yaml_reports_line(tmp_path: Path, registry: Registry) -> None:
    err = error_of(write(tmp_path, GOOD.replace("{max_steps: 100}", "{max_steps: 100")), registry)
    assert err.file is not None and err.line is not None and err.line >= 7
    assert "invalid YAML" in err.message


def test_missing_file(tmp_path: Path, registry: Registry) -> None:
    err = error_of(tmp_path / "nope.yaml", registry)
    assert err.file == str(tmp_path / "nope.yaml") and "not found" in err.message


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("", "empty"),
        ("- a\n- b\n", "mapping"),
        ("character: tiny\nseed: x\n", "seed"),
        ("character: tiny\nsim: {actuation: servo}\n", "sim.actuation"),
        ("character: tiny\nname: ../escape\n", "name"),
        ("character: tiny\nname: /etc/x\n", "name"),
        ("character: tiny\nname: ..\n", "name"),
        ("character: tiny\nseed: 1\nseed: 2\n", "duplicate key 'seed'"),
        ("a: " + "[" * 100 + "]" * 100 + "\n", "deeper than 64"),
        ("a: &a [x, x, x, x, x, x, x, x, x, x]\n"
         + "".join(f"{n}: &{n} [{', '.join([f'*{p}'] * 10)}]\n"
                   for p, n in zip("abcdef", "bcdefg", strict=True)),
         "more than 100000 values"),
    ],
)
def test_other_shapes_of_bad_input(tmp_path: Path, registry: Registry, text, needle) -> None:
    err = error_of(write(tmp_path, text), registry)
    assert needle in err.format()


def test_toml_recipe(tmp_path: Path, registry: Registry) -> None:
    text = 'character = "tiny"\nseed = 3\n[rewards.action_diff]\nweight = 0.5\n'
    resolved = load(write(tmp_path, text, "r.toml"), registry)
    assert resolved.recipe.seed == 3
    assert resolved.component("rewards.action_diff").config.weight == 0.5
    err = error_of(write(tmp_path, "character = \n", "bad.toml"), registry)
    assert "invalid TOML" in err.message and err.file.endswith("bad.toml")


def test_overrides_and_shorthands(tmp_path: Path, registry: Registry) -> None:
    path = write(tmp_path, GOOD)
    resolved = load(
        path,
        registry,
        shorthands={"seed": "7", "character": "tiny"},
        assignments=["rewards.action_diff.k=2.5", "terminations.episode_cap.max_steps=9"],
    )
    assert resolved.recipe.seed == 7
    assert resolved.component("rewards.action_diff").config.k == 2.5
    assert resolved.component("terminations.episode_cap").config.max_steps == 9


def test_override_error_points_at_the_flag(tmp_path: Path, registry: Registry) -> None:
    err = error_of(write(tmp_path, GOOD), registry, assignments=["rewards.action_diff.kk=1"])
    assert err.file == "command line (--set rewards.action_diff.kk=1)"
    assert err.field == "rewards.action_diff.kk"
    err = error_of(write(tmp_path, GOOD), registry, shorthands={"character": "dinoo"})
    assert "--character dinoo" in (err.file or "") and "unknown character" in err.message
    with pytest.raises(RecipeError, match="PATH=VALUE"):
        load(write(tmp_path, GOOD), registry, assignments=["novalue"])


def test_lock_file_round_trips(tmp_path: Path, registry: Registry) -> None:
    resolved = load(write(tmp_path, GOOD), registry, assignments=["seed=4"])
    lock = write_lock(resolved, tmp_path / "run")
    data = yaml.safe_load(lock.read_text())
    assert data["_lock"]["plugins"]["character"]["distribution"] == "local"
    assert data["_lock"]["overrides"] == {"seed": "--set seed=4"}
    data.pop("_lock")
    again = resolve(parse_text(yaml.safe_dump(data), "lock", ".yaml"), registry)
    assert again.to_dict() == resolved.to_dict()


def test_schema_lists_plugins_and_config_fields(registry: Registry) -> None:
    schema = recipe_schema(registry)
    branches = schema["$defs"]["reward_component"]["oneOf"]
    names = {b["properties"]["type"]["const"] for b in branches if "properties" in b}
    assert {"action_diff", "action_min"} <= names
    diff = next(
        b for b in branches if b.get("properties", {}).get("type") == {"const": "action_diff"}
    )
    assert set(diff["properties"]) == {"type", "weight", "k"}
    assert diff["additionalProperties"] is False
    assert schema["properties"]["rewards"]["additionalProperties"]["$ref"].endswith(
        "reward_component"
    )


def test_missing_requirement_is_caught_before_building(tmp_path: Path) -> None:
    class NeedsTail(retarget.RewardTerm):
        """Needs a site the tiny character lacks."""

        name = "needs_tail"
        requires = ("site:tail_tip",)

        def compute(self, ctx):
            return ctx.action.sum(-1)

    class Plugins:
        @retarget.hookimpl
        def register_rewards(self, register) -> None:
            register(NeedsTail)

    reg = load_plugins(strict=True, modules={"tiny": TinyPlugins(), "tail": Plugins()})
    err = error_of(write(tmp_path, "character: tiny\nrewards:\n  needs_tail: {}\n"), reg)
    assert err.field == "rewards.needs_tail" and "site:tail_tip" in err.message


def test_characters_without_a_recipe_file_get_their_table2_column(tmp_path) -> None:
    """`--character dino|oppy` alone starts from the character's packaged recipe; the human and
    Jesse keep the default (Jesse's column); a user's recipe file is laid over its character's."""
    import torch

    from retarget.env.build import env_from_recipe
    from retarget.recipe import load
    from retarget.registry.loader import load_plugins

    registry = load_plugins()
    for name in ("dino", "oppy"):
        r = load(None, registry, shorthands={"character": name}, assignments=[])
        cfg = {k.split(".", 1)[1]: c.config for k, c in r.components.items() if "." in k}
        assert cfg["foot_contact"].weight == 1.5
        assert cfg["action_diff"].k == 150.0
        assert cfg["link_pos"].bodies == ["root"]
        env = env_from_recipe(r, num_envs=2, threads=1)
        env.reset()
        _, reward, *_ = env.step(torch.zeros(2, env.action_dim))
        assert torch.isfinite(reward).all()
    for name in ("human", "jesse"):
        r = load(None, registry, shorthands={"character": name}, assignments=[])
        assert "rewards.foot_contact" not in r.components
        assert r.components["rewards.joint_pos"].config.weight == 4.0
    own = tmp_path / "mine.yaml"  # laid over dino's recipe: only what it says changes
    own.write_text("character: dino\nrewards:\n  joint_pos: {weight: 3.0}\n  action_min: null\n")
    r = load(str(own), registry, shorthands={}, assignments=[])
    rewards = {k.split(".", 1)[1]: c.config for k, c in r.components.items() if "rewards." in k}
    assert rewards["joint_pos"].weight == 3.0 and rewards["joint_pos"].k == 20.0  # dino's k
    assert "foot_contact" in rewards and "action_min" not in rewards  # null removes
    assert "algorithm" in r.components and "terminations.fall" in r.components
    alone = tmp_path / "alone.yaml"
    alone.write_text("extends: null\ncharacter: dino\nrewards:\n  joint_pos: {weight: 3.0}\n")
    r = load(str(alone), registry, shorthands={}, assignments=[])
    assert [k for k in r.components if k.startswith("rewards.")] == ["rewards.joint_pos"]


def test_named_packaged_recipes() -> None:
    """`retarget train paper` / `teacher --character dino`: packaged recipes by name, the
    character's own variant first; the default uses PD targets, `paper` the paper's torques."""
    registry = load_plugins()
    default = load(None, registry, shorthands={"character": "dino"})
    assert default.recipe.sim.actuation == "pd"
    assert default.component("algorithm").config.learning_rate == 4e-4
    paper = load("paper", registry, shorthands={"character": "dino"})
    assert paper.recipe.sim.actuation == "torque"
    assert paper.component("algorithm").config.learning_rate == 1.2e-4
    assert paper.components["rewards.foot_contact"].config.weight == 1.5  # Dino's column
    teacher = load("teacher", registry, shorthands={"character": "oppy"})
    assert [c.entry.name for c in teacher.of_kind("sensor")] == ["full_body", "reference_action"]
    assert teacher.component("algorithm").config.residual == "reference_action"
    with pytest.raises(RecipeError, match="not found") as err:
        load("no_such_recipe", registry)
    assert "teacher" in (err.value.hint or "")


def test_extends_a_named_recipe_a_file_and_refuses_loops(tmp_path) -> None:
    from retarget.recipe import load
    from retarget.registry.loader import load_plugins

    registry = load_plugins()
    base = tmp_path / "base.yaml"
    base.write_text("extends: teacher\nname: base\nenv: {num_envs: 8}\n")
    child = tmp_path / "sub" / "child.yaml"
    child.parent.mkdir()
    child.write_text("extends: ../base.yaml\nenv: {reset_lift: 0.05}\n")
    r = load(str(child), registry, shorthands={}, assignments=[])
    assert [c.entry.name for c in r.of_kind("sensor")] == ["full_body", "reference_action"]
    assert r.recipe.env.num_envs == 8 and r.recipe.env.reset_lift == 0.05  # merged, both kept
    assert r.recipe.name == "base" and r.recipe.extends is None
    loop_a, loop_b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    loop_a.write_text("extends: b.yaml\ncharacter: human\n")
    loop_b.write_text("extends: a.yaml\n")
    with pytest.raises(RecipeError, match="loops back"):
        load(str(loop_a), registry, shorthands={}, assignments=[])
    missing = tmp_path / "m.yaml"
    missing.write_text("extends: nowhere\ncharacter: human\n")
    with pytest.raises(RecipeError, match="no such packaged recipe or file"):
        load(str(missing), registry, shorthands={}, assignments=[])


def test_default_run_names_say_what_differs(tmp_path) -> None:
    from retarget.recipe import load
    from retarget.registry.loader import load_plugins
    from retarget.train.start import run_name

    registry = load_plugins()

    def name(recipe, **shorthands):
        r = load(recipe, registry, shorthands=shorthands, assignments=[])
        return run_name(r, [c.entry.name for c in r.of_kind("sensor")])

    mine = tmp_path / "stairs.yaml"
    mine.write_text("character: dino\nsensors: [hmd]\n")
    names = {
        name(None, character="dino", sensors="hmd"),
        name(str(mine)),
        name("paper", character="dino", sensors="hmd"),
        name(None, character="dino", sensors="hmd", scene="boxes", observers="height_map"),
    }
    assert names == {"dino-hmd", "stairs-dino-hmd", "paper-dino-hmd",
                     "dino-hmd-boxes-height_map"}  # fmt: skip


def test_lock_written_again_from_itself_keeps_its_provenance(
    tmp_path: Path, registry: Registry
) -> None:
    """`train --resume` resolves the run's own lock and writes it again: the lock still names
    the recipe and overrides the run began with, plus the resume's own."""
    first = load(write(tmp_path, GOOD), registry, assignments=["seed=4"])
    lock = write_lock(first, tmp_path / "run")
    again = load(lock, registry, assignments=["sim.threads=1"])
    data = yaml.safe_load(write_lock(again, tmp_path / "run").read_text())
    assert data["_lock"]["source"] == first.source.path
    assert data["_lock"]["overrides"] == {
        "seed": "--set seed=4",
        "sim.threads": "--set sim.threads=1",
    }
    other = yaml.safe_load(write_lock(again, tmp_path / "copy").read_text())
    assert other["_lock"]["source"] == again.source.path  # a lock read from elsewhere: as given
