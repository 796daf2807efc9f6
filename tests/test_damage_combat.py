"""`LearnedDamage` in the simulator's combat step, `load_damage_model`, and the wiring into
`decoy replay --models` and the environment."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import torch
from esta_fixtures import make_match, write_match
from trained_nets import trained_like
from typer.testing import CliRunner

import decoy_cli.damage
from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.damage import load_damage_model, shipped_models_installed
from decoy_cli.damage.combat import LearnedDamage
from decoy_cli.damage.features import PAPER_SPEC, WEAPONS, FeatureSpec, encode
from decoy_cli.damage.model_folder import load_dip, load_dog, save_dip, save_dog
from decoy_cli.damage.networks import DipNet, DogNet, tensors
from decoy_cli.env.parallel import DecoyParallelEnv
from decoy_cli.errors import ModelError
from decoy_cli.sim.combat import HIT_GROUPS, CombatBatch, VisiblePairs, make_batch
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.graph import STOP_ACTION

runner = CliRunner()
WIDE = {"COLUMNS": "220"}


def model_folder(
    folder: Path, fire: bool = False, dog_bias: float | None = None, seed: int = 0
) -> Path:
    """A model folder of random nets. DOG's damage is about 30 HP give or take a few tens;
    `fire`: DIP says 'hit' for every pair (logit 20); `dog_bias`: DOG's damage output is this
    constant (HP / 100)."""
    dip = trained_like(DipNet(), seed)
    dog = trained_like(DogNet(), seed + 1)
    with torch.no_grad():
        dog.vae_decoder.damage_regressor[0].weight.mul_(0.1)
        dog.vae_decoder.damage_regressor[0].bias.fill_(0.3)
        if fire:
            dip.classifier[4].weight.zero_()
            dip.classifier[4].bias.fill_(20.0)
        if dog_bias is not None:
            dog.vae_decoder.damage_regressor[0].weight.zero_()
            dog.vae_decoder.damage_regressor[0].bias.fill_(dog_bias)
    save_dip(folder, dip, FeatureSpec(), 0.5, {"test": True})
    save_dog(folder, dog, FeatureSpec(), {"test": True})
    return folder


def batch(k: int, seed: int = 0, weapons: list[str] | None = None) -> CombatBatch:
    """K random de_dust2 pairs (metres)."""
    rng = np.random.default_rng(seed)
    a = rng.uniform([-40, -20, -3], [34, 59, 3], (k, 3))
    v = rng.uniform([-40, -20, -3], [34, 59, 3], (k, 3))
    return CombatBatch(
        attacker=np.arange(k),
        victim=np.arange(k) + k,
        attacker_position=a,
        victim_position=v,
        attacker_yaw=rng.uniform(0, 360, k),
        victim_yaw=rng.uniform(0, 360, k),
        attacker_hp=rng.integers(1, 101, k).astype(np.int16),
        victim_hp=rng.integers(1, 101, k).astype(np.int16),
        attacker_weapon=np.array(weapons or rng.choice(WEAPONS, k).tolist(), dtype=object),
        victim_armor=rng.integers(0, 101, k).astype(np.int16),
        victim_helmet=rng.integers(0, 2, k).astype(bool),
        map_name="de_dust2",
    )


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return model_folder(tmp_path_factory.mktemp("models") / "random")


@pytest.fixture(scope="module")
def firing(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return model_folder(tmp_path_factory.mktemp("models") / "firing", fire=True)


def test_deterministic_under_a_seed(firing: Path) -> None:
    model = LearnedDamage(load_dip(firing), load_dog(firing))
    pairs = batch(40)
    first = model(pairs, np.random.default_rng(7))
    again = model(pairs, np.random.default_rng(7))
    other = model(pairs, np.random.default_rng(8))
    assert first.hit.all()  # the firing DIP hits every armed pair
    for name in ("damage", "hit_group", "hit"):
        np.testing.assert_array_equal(getattr(first, name), getattr(again, name))
    assert not np.array_equal(first.damage, other.damage)  # z differs with the seed


def test_threshold_firearms_and_damage_bounds(folder: Path) -> None:
    model = LearnedDamage(load_dip(folder), load_dog(folder))
    weapons = [*WEAPONS[:26], "Knife", "HE Grenade", "C4", "Zeus x27", "", *WEAPONS[26:]]
    pairs = batch(len(weapons), seed=2, weapons=weapons)
    probability = model.hit_probability(pairs)
    with torch.inference_mode():
        logits = model.dip.net(*tensors(encode(pairs, FeatureSpec())))
    np.testing.assert_allclose(probability, torch.sigmoid(logits).numpy(), rtol=1e-6)
    threshold = float(np.median(probability))
    chosen = LearnedDamage(model.dip, model.dog, threshold=threshold)
    result = chosen(pairs, np.random.default_rng(0))
    armed = np.array([w in WEAPONS for w in weapons])
    np.testing.assert_array_equal(result.hit, armed & (probability >= threshold))
    assert 0 < result.hit.sum() < len(weapons)
    hits = result.hit
    assert np.all(result.damage[hits] >= 1)
    assert np.all(result.damage[hits] <= pairs.victim_hp[hits])
    assert np.all((result.hit_group[hits] >= 0) & (result.hit_group[hits] < len(HIT_GROUPS)))
    assert np.all(result.damage[~hits] == 0) and np.all(result.hit_group[~hits] == -1)


def test_dog_runs_only_on_the_pairs_dip_selects(
    folder: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    model = LearnedDamage(load_dip(folder), load_dog(folder))
    pairs = batch(30, seed=4)
    threshold = float(np.quantile(model.hit_probability(pairs), 0.7))
    model = LearnedDamage(model.dip, model.dog, threshold=threshold)
    seen = []
    decode = model._dog

    def recording(x: torch.Tensor, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        seen.append(x.clone())
        return decode(x, z)

    monkeypatch.setattr(model, "_dog", recording)
    result = model(pairs, np.random.default_rng(1))
    assert len(seen) == 1  # one batched call
    rows = np.flatnonzero(result.hit)
    assert 0 < len(rows) < 30 and len(seen[0]) == len(rows)
    coords = torch.from_numpy(encode(pairs, model.dog.spec).coords[rows])
    torch.testing.assert_close(seen[0][:, 8:19], coords)  # after the 8 map columns
    # nothing hits: DOG is not called at all
    seen.clear()
    LearnedDamage(model.dip, model.dog, threshold=1.0)(pairs, np.random.default_rng(1))
    assert seen == []


def test_the_folded_networks_equal_the_modules(folder: Path) -> None:
    """The inference path folds BatchNorm into the Linears; outputs must not change."""
    dip, dog = load_dip(folder), load_dog(folder)
    model = LearnedDamage(dip, dog, threshold=0.0)
    for k, seed in ((1, 0), (7, 1), (300, 2)):
        pairs = batch(k, seed=seed)
        features = encode(pairs, FeatureSpec())
        with torch.inference_mode():
            logits = dip.net(*tensors(features))
            hp, group_logits = dog.net.generate(
                *tensors(features), generator=torch.Generator().manual_seed(seed)
            )
        np.testing.assert_allclose(
            model.hit_probability(pairs), torch.sigmoid(logits).numpy(), rtol=1e-5, atol=1e-6
        )
        z = torch.randn((k, 8), generator=torch.Generator().manual_seed(seed))
        stacked = np.concatenate(
            [features.map, features.coords, features.weapon, features.armor], 1
        )
        with torch.inference_mode():
            fast_hp, fast_logits = model._dog(torch.from_numpy(stacked), z)
        torch.testing.assert_close(fast_hp, hp, rtol=1e-5, atol=1e-3)
        torch.testing.assert_close(fast_logits, group_logits, rtol=1e-5, atol=1e-4)


def test_dip_and_dog_may_use_different_features(folder: Path, tmp_path: Path) -> None:
    dip = load_dip(folder)
    paper_dog = trained_like(DogNet(), 3)
    save_dog(tmp_path, paper_dog, PAPER_SPEC)
    dog = load_dog(tmp_path)
    pairs = batch(12, seed=5)
    result = LearnedDamage(dip, dog, threshold=0.0)(pairs, np.random.default_rng(3))
    generator = torch.Generator().manual_seed(int(np.random.default_rng(3).integers(2**63)))
    with torch.inference_mode():
        hp, logits = dog.net.generate(*tensors(encode(pairs, PAPER_SPEC)), generator=generator)
    expected = np.clip(np.rint(hp.numpy()), 1, pairs.victim_hp)
    np.testing.assert_array_equal(result.damage, expected)
    np.testing.assert_array_equal(result.hit_group, logits.argmax(1).numpy())


@pytest.mark.parametrize(("bias", "expected"), [(-5.0, "one"), (5.0, "victim_hp")])
def test_damage_is_clipped_to_one_and_the_victims_hp(
    tmp_path: Path, bias: float, expected: str
) -> None:
    folder = model_folder(tmp_path, fire=True, dog_bias=bias)
    pairs = batch(10, seed=6)
    result = load_damage_model(str(folder))(pairs, np.random.default_rng(0))
    assert result.hit.all()
    want = np.ones(10) if expected == "one" else pairs.victim_hp
    np.testing.assert_array_equal(result.damage, want)


def test_inference_threads_are_restored(folder: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    monkeypatch.setattr(torch, "get_num_threads", lambda: 2)
    monkeypatch.setattr(torch, "set_num_threads", calls.append)
    pairs = batch(6)
    LearnedDamage(load_dip(folder), load_dog(folder), threshold=0.0)(
        pairs, np.random.default_rng(0)
    )
    assert calls == [1, 2, 1, 2]  # DIP, then DOG, each on one thread, restored after
    calls.clear()
    LearnedDamage(load_dip(folder), load_dog(folder), threads=None).hit_probability(pairs)
    assert calls == []
    with pytest.raises(ValueError, match="threads must be >= 1"):
        LearnedDamage(load_dip(folder), load_dog(folder), threads=0)


def test_an_empty_batch(folder: Path) -> None:
    result = LearnedDamage(load_dip(folder), load_dog(folder))(batch(0), np.random.default_rng(0))
    assert len(result) == 0


def test_simulator_and_training_batches_encode_alike() -> None:
    """The simulator builds its batch from agents (make_batch); training builds one from ESTA
    rows by hand: one `encode` gives the same features for the same states."""
    u = 1 / HAMMER_TO_M
    agents = Agents.create(
        names=["t", "ct"],
        sides=["T", "CT"],
        positions=np.array([[1.0, 2.0, 0.5], [-3.0, 10.0, 0.0]]),
        nodes=np.zeros(2, np.int64),
        weapons=["AK-47", "M4A4"],
        hp=np.array([80, 64]),
        armor=np.array([100, 0]),
        helmet=np.array([True, False]),
        yaw=np.array([45.0, 300.0]),
    )
    simulated = make_batch(agents, VisiblePairs(np.array([0, 1]), np.array([1, 0])), "de_dust2")
    esta_u = np.array([[1.0, 2.0, 0.5], [-3.0, 10.0, 0.0]]) * u  # Hammer units, as in ESTA
    position = esta_u * HAMMER_TO_M  # the reader converts once
    hand = CombatBatch(
        attacker=np.array([0, 1]),
        victim=np.array([1, 0]),
        attacker_position=position,
        victim_position=position[::-1],
        attacker_yaw=np.array([45.0, 300.0]),
        victim_yaw=np.array([300.0, 45.0]),
        attacker_hp=np.array([80, 64], np.int16),
        victim_hp=np.array([64, 80], np.int16),
        attacker_weapon=np.array(["AK-47", "M4A4"], dtype=object),
        victim_armor=np.array([0, 100], np.int16),
        victim_helmet=np.array([False, True]),
        map_name="de_dust2",
    )
    for spec in (FeatureSpec(), PAPER_SPEC):
        a, b = encode(simulated, spec), encode(hand, spec)
        for name in ("map", "coords", "weapon", "armor"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-6, atol=1e-6)


# ---- choosing a model -------------------------------------------------------------------------


def test_load_damage_model_choices(
    folder: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert load_damage_model("none") is None
    model = load_damage_model(str(folder))
    assert isinstance(model, LearnedDamage) and model.threshold == 0.5
    monkeypatch.setattr(decoy_cli.damage, "SHIPPED_MODELS", tmp_path / "models")
    assert not shipped_models_installed()
    with pytest.raises(ModelError, match=r"no shipped damage models in .*models: pass a model"):
        load_damage_model("shipped")
    model_folder(tmp_path / "models")
    assert shipped_models_installed()
    assert isinstance(load_damage_model("shipped"), LearnedDamage)
    with pytest.raises(ModelError, match="nowhere: no such model folder"):
        load_damage_model(str(tmp_path / "nowhere"))
    only_dip = tmp_path / "only-dip"
    save_dip(only_dip, DipNet(), FeatureSpec(), 0.5)
    with pytest.raises(ModelError, match=r"no dog\.json"):
        load_damage_model(str(only_dip))


# ---- decoy replay --models --------------------------------------------------------------------


@pytest.fixture(scope="module")
def match_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_match(tmp_path_factory.mktemp("match") / "m.json.xz", make_match())


def _replay(*args: str):
    return runner.invoke(app, ["replay", *args], env=WIDE)


def test_replay_with_a_model_folder_shoots(match_file: Path, firing: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = _replay(f"{match_file}:1", "--models", str(firing), "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "combat on" in result.stdout
    events = pd.read_csv(out / "events.csv")
    damage = events[events["kind"] == "damage"]
    assert len(damage) > 0
    assert (damage["tick"] % 30 == 0).all()  # only the combat step, every 30 ticks, shoots
    data = [json.loads(d) for d in damage["data"]]
    assert all(d["damage"] >= 1 and d["hit_group"] in range(6) for d in data)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["options"]["combat"] is True and summary["damage_models"] == str(firing)
    # the same seed gives the same shots
    again = _replay(f"{match_file}:1", "--models", str(firing), "--out", str(tmp_path / "again"))
    assert again.exit_code == 0
    pd.testing.assert_frame_equal(events, pd.read_csv(tmp_path / "again" / "events.csv"))


def test_replay_model_choices_without_shooting(
    match_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """--models none replays without shooting and says so; the default (shipped) is an error
    line when the shipped models are not installed, never a silent replay without combat."""
    monkeypatch.setattr(decoy_cli.damage, "SHIPPED_MODELS", tmp_path / "not-installed")
    result = _replay(f"{match_file}:1", "--models", "none", "--out", str(tmp_path / "a"))
    assert result.exit_code == 0 and "combat off" in result.stdout
    assert "--models none" in result.stdout
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["damage_models"] is None
    result = _replay(f"{match_file}:1", "--out", str(tmp_path / "b"))
    assert result.exit_code == 1 and "no shipped damage models" in result.output


@pytest.mark.parametrize(
    ("models", "expected"),
    [
        ("shipped", "error: no shipped damage models in {tmp}/not-installed: pass a model folder"),
        ("{tmp}/nowhere", "error: {tmp}/nowhere: no such model folder"),
        ("{tmp}", "error: {tmp}: no dip.json"),
    ],
    ids=["shipped-missing", "no-folder", "not-a-model-folder"],
)
def test_replay_bad_models_are_one_error_line(
    match_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, models: str, expected: str
) -> None:
    monkeypatch.setattr(decoy_cli.damage, "SHIPPED_MODELS", tmp_path / "not-installed")
    result = _replay(f"{match_file}:1", "--models", models.format(tmp=tmp_path))
    assert result.exit_code == 1
    assert result.stderr.startswith(expected.format(tmp=tmp_path))
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output


# ---- the environment --------------------------------------------------------------------------


def test_environment_takes_a_model_loader(tmp_path: Path) -> None:
    lethal = model_folder(tmp_path / "lethal", fire=True, dog_bias=5.0)
    none = DecoyParallelEnv(n_t=1, n_ct=1, damage_model=lambda: load_damage_model("none"))
    assert none.damage_model is None and not none.setup.shooting
    with pytest.raises(ModelError, match="no such model folder"):
        DecoyParallelEnv(damage_model=lambda: load_damage_model(str(tmp_path / "nowhere")))
    env = DecoyParallelEnv(
        n_t=1, n_ct=1, damage_model=lambda: load_damage_model(str(lethal)), bomb=False
    )
    assert isinstance(env.damage_model, LearnedDamage)
    try:
        env.reset(seed=0)
        graph = env.graph
        node = env.sim.agents.node[0]
        beside = graph.edge_target[graph.out_edges[node][graph.out_edges[node] >= 0][0]]
        env.sim.relocate(1, int(beside))  # ct_0 next to t_0: they see each other
        for _ in range(5):
            if not env.agents:
                break
            env.step(dict.fromkeys(env.agents, STOP_ACTION))
        kinds = [event.kind for event in env.sim.events]
        assert "damage" in kinds and "kill" in kinds
    finally:
        env.close()


def test_a_calibrated_dip_decides_by_its_rule(folder: Path, tmp_path: Path) -> None:
    import shutil

    from decoy_cli.damage.calibration import Calibration
    from decoy_cli.damage.model_folder import save_calibration

    calibrated = tmp_path / "calibrated"
    shutil.copytree(folder, calibrated)
    logit = float(np.log(0.3 / 0.7))
    # a = 0: every pair's calibrated probability is 0.3, whatever the DIP says
    save_calibration(calibrated, Calibration("platt", 0.0, logit, 0.5, "bernoulli"))
    pairs = batch(4000, seed=5, weapons=["AK-47"] * 4000)
    model = LearnedDamage(load_dip(calibrated), load_dog(calibrated))
    hit = model(pairs, np.random.default_rng(9)).hit
    assert abs(hit.mean() - 0.3) < 0.03
    # the threshold rule on the same constant 0.3 < 0.5: nobody is hit
    save_calibration(calibrated, Calibration("platt", 0.0, logit, 0.5, "threshold"))
    model = LearnedDamage(load_dip(calibrated), load_dog(calibrated))
    assert not model(pairs, np.random.default_rng(9)).hit.any()
    # an explicit threshold overrides the calibration: the raw DIP decides
    raw = LearnedDamage(load_dip(calibrated), load_dog(calibrated), threshold=0.5)
    plain = LearnedDamage(load_dip(folder), load_dog(folder), threshold=0.5)
    rng_a, rng_b = np.random.default_rng(2), np.random.default_rng(2)
    np.testing.assert_array_equal(raw(pairs, rng_a).hit, plain(pairs, rng_b).hit)


def test_rules_damage_is_the_rules_per_bullet(firing: Path) -> None:
    from decoy_cli.damage.bullet_counts import BulletCounts
    from decoy_cli.damage.hit_groups import GROUPS, HitGroupModel
    from decoy_cli.damage.rules import shot_damage
    from decoy_cli.damage.rules_damage import RulesDamage, RulesFile

    rng = np.random.default_rng(61)
    groups = [GROUPS[i] for i in rng.integers(0, 6, 600)]
    hit_groups = HitGroupModel.fit(["AK-47"] * 600, rng.uniform(100, 2000, 600), groups)
    single = BulletCounts()
    single.add("AK-47", 500.0, 1)  # every damaging step lands one bullet
    model = RulesDamage(load_dip(firing), RulesFile(hit_groups, single))
    pairs = batch(300, seed=6, weapons=["AK-47"] * 299 + ["Knife"])
    first = model(pairs, np.random.default_rng(4))
    again = model(pairs, np.random.default_rng(4))
    np.testing.assert_array_equal(first.damage, again.damage)
    assert first.hit[:299].all() and not first.hit[299]  # the knife never hits here
    assert first.armor_damage is not None
    for k in np.flatnonzero(first.hit):
        bullet = shot_damage(
            "AK-47",
            HIT_GROUPS[first.hit_group[k]],
            pairs.distance[k] / HAMMER_TO_M,
            armor=int(pairs.victim_armor[k]),
            helmet=bool(pairs.victim_helmet[k]),
        )
        assert first.damage[k] == min(max(bullet.health, 1), max(int(pairs.victim_hp[k]), 1))
        assert first.armor_damage[k] == min(bullet.armor, int(pairs.victim_armor[k]))


def test_penetration_learned_from_hits_below_the_rules() -> None:
    from decoy_cli.damage.rules import shot_damage
    from decoy_cli.damage.rules_damage import Penetration

    least = shot_damage("AK-47", "Chest", 800.0, armor=100, helmet=True).health
    bare = shot_damage("AK-47", "Chest", 800.0, armor=0, helmet=False).health
    through = Penetration.learn(
        ["AK-47"] * 4, ["Chest", "Chest", "Chest", "LeftArm"], [800.0] * 4,
        [least, bare, least // 2, 1],
    )  # fmt: skip
    assert through.hits == 4  # the rules' own values are clear paths, armour or not
    assert through.shares == pytest.approx([(least // 2) / least, 1 / shot_damage(
        "AK-47", "Arm", 800.0, armor=100, helmet=True).health])  # fmt: skip
    rng = np.random.default_rng(0)
    factors = np.array([through.factor(rng) for _ in range(4000)])
    assert abs(np.mean(factors < 1.0) - 0.5) < 0.03  # half the bullets go through something
    assert set(np.round(factors[factors < 1.0], 6)) == set(np.round(through.shares, 6))
    clear = Penetration()
    before = np.random.default_rng(5)
    assert clear.factor(before) == 1.0
    after = np.random.default_rng(5)
    after.random(2)
    assert before.random() == after.random()  # two draws either way: streams stay aligned


def test_the_shipped_rules_are_a_models_choice() -> None:
    from decoy_cli.damage.rules_damage import RulesDamage

    if not shipped_models_installed():
        pytest.skip("no shipped models")
    model = load_damage_model("rules")
    assert isinstance(model, RulesDamage)
    assert model.rules.provenance["hits"] == 396


def test_rules_bullets_wear_armour_down_one_after_another() -> None:
    from decoy_cli.damage.bullet_counts import BulletCounts
    from decoy_cli.damage.hit_groups import HitGroupModel
    from decoy_cli.damage.rules_damage import RulesFile, pair_outcome

    three = BulletCounts()
    three.add("AK-47", 800.0, 3)
    hit_groups = HitGroupModel.fit(["AK-47"], [800.0], ["Chest"])
    hit_groups.sample = lambda rng, weapons, distances: ["Chest"] * len(weapons)  # type: ignore[method-assign]
    rules = RulesFile(hit_groups, three)
    # AK-47 chest at 800 u does 34.86: with 5 armour 27 HP and 3 armour, then with 2 armour
    # left 34.86 - 2 / 0.5 = 30 HP and 2 armour, then 34 HP bare
    health, taken, group = pair_outcome(rules, "AK-47", 800.0, 5, False, np.random.default_rng(0))
    assert (health, taken, group) == (27 + 30 + 34, 5, "Chest")


def test_bernoulli_hits_and_rules_outcomes_draw_from_separate_streams(firing: Path) -> None:
    import shutil

    from decoy_cli.damage.calibration import Calibration
    from decoy_cli.damage.model_folder import save_calibration
    from decoy_cli.damage.rules_damage import RulesDamage, RulesFile

    if not shipped_models_installed():
        pytest.skip("no shipped models")
    rules = RulesFile.load(decoy_cli.damage.SHIPPED_MODELS)
    folder = Path(str(firing) + "-bernoulli")
    shutil.copytree(firing, folder, dirs_exist_ok=True)
    save_calibration(folder, Calibration("platt", 0.0, 0.0, 0.5, "bernoulli"))  # p' = 0.5
    model = RulesDamage(load_dip(folder), rules)
    pairs = batch(1, seed=3, weapons=["AK-47"])
    pairs.victim_hp[:] = 100
    pairs.victim_armor[:] = 0
    rng = np.random.default_rng(11)
    damage = [model(pairs, rng).damage[0] for _ in range(3000)]
    hits = np.array(damage)[np.array(damage) > 0]
    assert 0.45 < len(hits) / 3000 < 0.55
    # more than one bullet lands in some steps, as the fitted counts say (a shared stream made
    # every Bernoulli hit a one-bullet step)
    assert np.mean(hits > 40) > 0.1
