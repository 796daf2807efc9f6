"""DIP and DOG, the paper's damage networks (torch; import this module only where torch is due).

Both share a game-state encoder of four branches, Linear -> [BatchNorm] -> ReLU of width 32 each
over the four feature blocks of decoy_cli/damage/features.py (map 8, coords 11, weapon 34,
armor 2), concatenated to 128: DIP's branches have no BatchNorm, DOG's have.

* DIP, the Damage Indicator Predictor: encoder -> Linear(128, 128) -> BatchNorm -> ReLU ->
  Dropout(0.3) -> Linear(128, 1), a logit: does the attacker damage the victim in this 0.5 s
  step (trained with BCE, thresholded at inference).
* DOG, the Damage Outcome Generator, a conditional VAE: the damage (HP / 100) and the hit-group
  one-hot are embedded (Linear -> BatchNorm -> ReLU, 1 -> 32 and 6 -> 32), concatenated with the
  128 condition (192) -> 256 -> 128 -> 64 (each Linear -> BatchNorm -> ReLU -> Dropout) -> mu and
  log-variance of the 8-dimensional latent; the decoder maps [z, condition] (136) -> 64 -> 128
  -> 256 (same blocks) to the damage (one Linear, HP / 100) and 6 hit-group logits in the order
  of `HIT_GROUPS` (Head, Neck, Chest, Stomach, Arm, Leg). At inference z ~ N(0, I).

Layer names and shapes are those of the published checkpoints (HATS-ICT/decoy), so their state
dicts load as they are, except that their hit-group order is Head, Neck, Stomach, Chest, Arm,
Leg: decoy_cli/modeling/paper_import.py permutes those rows and columns on import.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import torch
from torch import Tensor, nn

from decoy_cli.damage.features import COORDS, HIT_GROUPS, MAPS, WEAPONS, Features

BRANCH_WIDTH = 32
CONDITION_WIDTH = 4 * BRANCH_WIDTH
LATENT = 8
DROPOUT = 0.3


def _branch(inputs: int, batchnorm: bool) -> nn.Sequential:
    """Linear -> [BatchNorm] -> ReLU to BRANCH_WIDTH."""
    layers: list[nn.Module] = [nn.Linear(inputs, BRANCH_WIDTH)]
    if batchnorm:
        layers.append(nn.BatchNorm1d(BRANCH_WIDTH))
    layers.append(nn.ReLU())
    return nn.Sequential(*layers)


def _mlp(widths: list[int], dropout: float) -> nn.Sequential:
    """Blocks Linear -> BatchNorm -> ReLU -> Dropout through `widths`."""
    layers: list[nn.Module] = []
    for inputs, outputs in pairwise(widths):
        layers += [
            nn.Linear(inputs, outputs),
            nn.BatchNorm1d(outputs),
            nn.ReLU(),
            nn.Dropout(dropout),
        ]
    return nn.Sequential(*layers)


class GameStateEncoder(nn.Module):
    """The four feature branches, concatenated to a (K, 128) condition."""

    def __init__(self, batchnorm: bool) -> None:
        super().__init__()
        self.map_embed = _branch(len(MAPS), batchnorm)
        self.coords_embed = _branch(COORDS, batchnorm)
        self.weapon_embed = _branch(len(WEAPONS), batchnorm)
        self.armor_embed = _branch(2, batchnorm)

    def forward(self, map: Tensor, coords: Tensor, weapon: Tensor, armor: Tensor) -> Tensor:
        return torch.cat(
            [
                self.map_embed(map),
                self.coords_embed(coords),
                self.weapon_embed(weapon),
                self.armor_embed(armor),
            ],
            dim=1,
        )


class DipNet(nn.Module):
    """Damage Indicator Predictor: one logit per pair (see the module docstring)."""

    def __init__(self, dropout: float = DROPOUT) -> None:
        super().__init__()
        self.game_state_encoder = GameStateEncoder(batchnorm=False)
        self.classifier = nn.Sequential(
            nn.Linear(CONDITION_WIDTH, CONDITION_WIDTH),
            nn.BatchNorm1d(CONDITION_WIDTH),
            nn.ReLU(),
            nn.Dropout(dropout),
            nn.Linear(CONDITION_WIDTH, 1),
        )

    def forward(self, map: Tensor, coords: Tensor, weapon: Tensor, armor: Tensor) -> Tensor:
        """(K,) logits."""
        condition = self.game_state_encoder(map, coords, weapon, armor)
        return self.classifier(condition).squeeze(1)


class _VaeEncoder(nn.Module):
    def __init__(self, dropout: float) -> None:
        super().__init__()
        self.damage_value_embed = _branch(1, batchnorm=True)
        self.hit_group_embed = _branch(len(HIT_GROUPS), batchnorm=True)
        self.encoder = _mlp([2 * BRANCH_WIDTH + CONDITION_WIDTH, 256, 128, 64], dropout)
        self.mu_layer = nn.Linear(64, LATENT)
        self.logvar_layer = nn.Linear(64, LATENT)

    def forward(
        self, damage: Tensor, hit_group: Tensor, condition: Tensor
    ) -> tuple[Tensor, Tensor]:
        hidden = self.encoder(
            torch.cat(
                [self.damage_value_embed(damage), self.hit_group_embed(hit_group), condition], 1
            )
        )
        return self.mu_layer(hidden), self.logvar_layer(hidden)


class _VaeDecoder(nn.Module):
    def __init__(self, dropout: float) -> None:
        super().__init__()
        self.decoder = _mlp([LATENT + CONDITION_WIDTH, 64, 128, 256], dropout)
        self.damage_regressor = nn.Sequential(nn.Linear(256, 1))
        self.hit_group_classifier = nn.Linear(256, len(HIT_GROUPS))

    def forward(self, z: Tensor, condition: Tensor) -> tuple[Tensor, Tensor]:
        hidden = self.decoder(torch.cat([z, condition], 1))
        return self.damage_regressor(hidden), self.hit_group_classifier(hidden)


@dataclass
class DogOutput:
    """DOG's reconstruction: damage (K, 1) in HP / 100, hit-group logits (K, 6), and the
    posterior's mu and log-variance (K, 8)."""

    damage: Tensor
    hit_logits: Tensor
    mu: Tensor
    logvar: Tensor


class DogNet(nn.Module):
    """Damage Outcome Generator, a conditional VAE (see the module docstring)."""

    def __init__(self, dropout: float = DROPOUT) -> None:
        super().__init__()
        self.game_state_encoder = GameStateEncoder(batchnorm=True)
        self.vae_encoder = _VaeEncoder(dropout)
        self.vae_decoder = _VaeDecoder(dropout)

    def forward(
        self,
        damage: Tensor,
        hit_group_onehot: Tensor,
        map: Tensor,
        coords: Tensor,
        weapon: Tensor,
        armor: Tensor,
        generator: torch.Generator | None = None,
    ) -> DogOutput:
        """Encode the true outcome, sample z = mu + sigma * eps (eps from `generator`, else
        torch's global generator) and decode: the training pass and reconstruction mode."""
        condition = self.game_state_encoder(map, coords, weapon, armor)
        mu, logvar = self.vae_encoder(damage, hit_group_onehot, condition)
        eps = torch.randn(mu.shape, generator=generator, dtype=mu.dtype, device=mu.device)
        z = mu + eps * torch.exp(0.5 * logvar)
        damage_out, hit_logits = self.vae_decoder(z, condition)
        return DogOutput(damage_out, hit_logits, mu, logvar)

    def generate(
        self,
        map: Tensor,
        coords: Tensor,
        weapon: Tensor,
        armor: Tensor,
        generator: torch.Generator,
    ) -> tuple[Tensor, Tensor]:
        """Sample z ~ N(0, I) (drawn first from `generator`, shape (K, 8)) and decode:
        damage in HP (K,), the decoder's output times 100 without clipping, and (K, 6) logits."""
        condition = self.game_state_encoder(map, coords, weapon, armor)
        z = torch.randn((len(condition), LATENT), generator=generator, dtype=condition.dtype)
        damage, hit_logits = self.vae_decoder(z, condition)
        return 100.0 * damage.squeeze(1), hit_logits


def tensors(features: Features) -> tuple[Tensor, Tensor, Tensor, Tensor]:
    """The four feature blocks as float32 CPU tensors (sharing memory with the arrays)."""
    return tuple(  # type: ignore[return-value]
        torch.from_numpy(np.ascontiguousarray(block, dtype=np.float32))
        for block in (features.map, features.coords, features.weapon, features.armor)
    )
