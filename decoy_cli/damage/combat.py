"""`LearnedDamage`: the simulator's damage model over a DIP and a DOG, as in the paper.

Per combat step (decoy_cli/sim/combat.py calls it with every visible ordered pair):

1. one batched DIP forward pass over all pairs gives the probability that the attacker damages
   the victim in this 0.5 s step (`DipDecision`, which `RulesDamage` shares); a pair hits when
   it reaches the threshold (the model folder's, 0.444 for the paper's DIP; the folder's fight
   threshold when `decoy models fight-threshold` set one), or by the rule of the folder's
   calibration (decoy_cli/damage/calibration.py), and the attacker holds a firearm
   of the vocabulary (the models know
   only firearm damage: a knife, grenade, C4, Zeus or empty hand deals none here);
2. one batched DOG pass over the hitting pairs only: z ~ N(0, I) from a torch generator seeded
   by the simulator's numpy generator (so a seeded simulation is reproducible), decoded to a
   damage and hit-group logits; the hit group is the most likely one given z (the paper's rule),
   the damage is rounded to whole HP and kept between 1 (a hit always hurts) and the victim's
   HP (the HP it can lose, as ESTA's hpDamageTaken).

Speed: a combat step has a few dozen pairs, where the Python overhead of nn.Module calls costs
more than the arithmetic. So at construction each network's eval-mode forward is folded into a
few matrix products: every BatchNorm into the Linear before it
(`torch.nn.utils.fusion.fuse_linear_bn_eval`), the four encoder branches into one block-diagonal
Linear over the concatenated features, DOG's two heads into one, Dropout dropped (the identity in
eval mode). The result equals the modules' forward up to float rounding (tested); it is a
snapshot: later changes to the networks' weights are not seen. The folding makes a small
step's inference several times faster (benchmarks/bench/bench_damage.py measures it).

Threads: by default the inference runs on one torch thread (the previous count is restored
after each call): on machines shared with other jobs, torch's default of one thread per core
made small products many times slower, while on an idle machine it saved little, and only on
the largest batches (benchmarks/bench/bench_damage.py). `threads=None` keeps torch's setting.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import torch
from torch import Tensor, nn
from torch.nn.utils.fusion import fuse_linear_bn_eval

from decoy_cli.damage.features import Features, encode, weapon_index
from decoy_cli.damage.model_folder import LoadedDip, LoadedDog
from decoy_cli.damage.networks import LATENT, DipNet, DogNet, GameStateEncoder
from decoy_cli.sim.combat import NO_HIT, CombatBatch, DamageResult

Layer = tuple[Tensor, Tensor]
"""A folded Linear: (weight transposed, inputs x outputs; bias)."""


def _fold(layers: nn.Sequential) -> list[Layer]:
    """Every Linear of an eval-mode Sequential with the BatchNorm that follows it folded in."""
    modules = list(layers)
    folded = []
    for k, module in enumerate(modules):
        if isinstance(module, nn.Linear):
            after = modules[k + 1] if k + 1 < len(modules) else None
            if isinstance(after, nn.BatchNorm1d):
                module = fuse_linear_bn_eval(module, after)
            folded.append((module.weight.detach().t().contiguous(), module.bias.detach().clone()))
    return folded


def _encoder(encoder: GameStateEncoder) -> Layer:
    """The four branches as one Linear from the concatenated features (55) to the condition."""
    parts = [
        _fold(branch)[0]
        for branch in (
            encoder.map_embed,
            encoder.coords_embed,
            encoder.weapon_embed,
            encoder.armor_embed,
        )
    ]
    return torch.block_diag(*(w for w, _ in parts)), torch.cat([b for _, b in parts])


def _relu_chain(h: Tensor, layers: list[Layer]) -> Tensor:
    for weight, bias in layers:
        h = torch.relu(torch.addmm(bias, h, weight))
    return h


class _FoldedDip:
    """DIP's eval-mode forward as three matrix products."""

    def __init__(self, net: DipNet) -> None:
        net.eval()
        layers = _fold(net.classifier)
        self.hidden = [_encoder(net.game_state_encoder), *layers[:-1]]
        self.out = layers[-1]

    def __call__(self, x: Tensor) -> Tensor:
        """(K,) logits of the (K, 55) concatenated features."""
        return torch.addmm(self.out[1], _relu_chain(x, self.hidden), self.out[0]).squeeze(1)


class _FoldedDogDecoder:
    """DOG's generation path (condition, then decoder from [z, condition]) as five products."""

    def __init__(self, net: DogNet) -> None:
        net.eval()
        self.encoder = [_encoder(net.game_state_encoder)]
        self.decoder = _fold(net.vae_decoder.decoder)
        damage = _fold(net.vae_decoder.damage_regressor)[0]
        groups = _fold(nn.Sequential(net.vae_decoder.hit_group_classifier))[0]
        self.heads = (torch.cat([damage[0], groups[0]], 1), torch.cat([damage[1], groups[1]]))

    def __call__(self, x: Tensor, z: Tensor) -> tuple[Tensor, Tensor]:
        """Damage in HP (K,) and hit-group logits (K, 6) of the (K, 55) features and z (K, 8)."""
        h = _relu_chain(torch.cat([z, _relu_chain(x, self.encoder)], 1), self.decoder)
        out = torch.addmm(self.heads[1], h, self.heads[0])
        return 100.0 * out[:, 0], out[:, 1:]


def _stacked(features: Features) -> Tensor:
    """The four feature blocks side by side, (K, 55) float32, in the encoder's order."""
    blocks = (features.map, features.coords, features.weapon, features.armor)
    return torch.from_numpy(np.concatenate(blocks, axis=1))


class DipDecision:
    """DIP's part of a damage model: the batched probability that each attacker damages its
    victim in the step, and the decision. `threshold` overrides the DIP's own; a DIP with a
    calibration (`decoy models calibrate`) decides by its rule, threshold or Bernoulli on the
    calibrated probability, unless a `threshold` is given. Only armed attackers (a firearm of
    the vocabulary) hit. `threads` is the torch thread count of the inference (None: torch's
    own setting)."""

    def __init__(
        self, dip: LoadedDip, threshold: float | None = None, threads: int | None = 1
    ) -> None:
        if threads is not None and threads < 1:
            raise ValueError(f"threads must be >= 1 or None, got {threads}")
        self.dip = dip
        self.threads = threads
        self.threshold = dip.decision_threshold if threshold is None else float(threshold)
        self.calibration = dip.calibration if threshold is None else None
        if not 0.0 <= self.threshold <= 1.0:
            raise ValueError(f"a DIP threshold is a probability, got {self.threshold}")
        with torch.no_grad():
            self._dip = _FoldedDip(dip.net)

    @contextmanager
    def inference(self) -> Iterator[None]:
        """torch inference mode on `self.threads` threads, restored afterwards."""
        previous = torch.get_num_threads()
        threads = self.threads
        change = threads is not None and threads != previous
        if threads is not None and change:
            torch.set_num_threads(threads)
        try:
            with torch.inference_mode():
                yield
        finally:
            if change:
                torch.set_num_threads(previous)

    def hit_probability(self, batch: CombatBatch, features: Features | None = None) -> np.ndarray:
        """(K,) DIP's probability that each attacker damages its victim in this step."""
        if len(batch) == 0:
            return np.zeros(0)
        if features is None:
            features = encode(batch, self.dip.spec)
        with self.inference():
            logits = self._dip(_stacked(features))
        return torch.sigmoid(logits).numpy().astype(np.float64)

    def hits(
        self, batch: CombatBatch, features: Features, seed: int | np.random.SeedSequence
    ) -> np.ndarray:
        """(K,) bool: the pairs that hit (class doc); `seed` drives Bernoulli decisions."""
        probability = self.hit_probability(batch, features)
        able = armed(batch)
        if self.calibration is not None:
            return able & self.calibration.decide(probability, np.random.default_rng(seed))
        return able & (probability >= self.threshold)


def armed(batch: CombatBatch) -> np.ndarray:
    """(K,) bool: attackers that can hit at all, holding a firearm of the models' vocabulary."""
    return weapon_index(batch.attacker_weapon) >= 0


class LearnedDamage:
    """A `DamageModel` from a loaded DIP and DOG: DIP decides who hits (`DipDecision`, which
    takes `threshold` and `threads`), DOG how much and where."""

    def __init__(
        self,
        dip: LoadedDip,
        dog: LoadedDog,
        threshold: float | None = None,
        threads: int | None = 1,
    ) -> None:
        self.decision = DipDecision(dip, threshold, threads)
        self.dip = dip
        self.dog = dog
        self.threshold = self.decision.threshold
        with torch.no_grad():
            self._dog = _FoldedDogDecoder(dog.net)

    def hit_probability(self, batch: CombatBatch) -> np.ndarray:
        """(K,) the probability that each attacker damages its victim in this step."""
        return self.decision.hit_probability(batch)

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        k = len(batch)
        seed = int(rng.integers(2**63))  # drawn every call: the stream does not depend on hits
        damage = np.zeros(k, dtype=np.int64)
        group = np.full(k, NO_HIT, dtype=np.int8)
        if k == 0:
            return DamageResult(damage, group, np.zeros(0, dtype=bool))
        decision = self.decision
        features = encode(batch, decision.dip.spec)
        hit = decision.hits(batch, features, seed)
        rows = np.flatnonzero(hit)
        if len(rows):
            if self.dog.spec != decision.dip.spec:
                features = encode(batch, self.dog.spec)
            generator = torch.Generator().manual_seed(seed)
            with decision.inference():
                # z first, as DogNet.generate draws it
                z = torch.randn((len(rows), LATENT), generator=generator)
                hp, logits = self._dog(_stacked(features.take(rows)), z)
            most = np.maximum(np.asarray(batch.victim_hp, dtype=np.int64)[rows], 1)
            damage[rows] = np.clip(np.rint(hp.numpy()).astype(np.int64), 1, most)
            group[rows] = logits.argmax(dim=1).numpy()
        return DamageResult(damage, group, hit)
