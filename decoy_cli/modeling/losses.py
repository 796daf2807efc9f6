"""DOG's training loss (DIP's is torch's binary cross-entropy on its logit, in training.py).

Kept apart from decoy_cli/damage/networks.py so that the networks the simulator loads carry no
training code: the run-time package imports nothing of this one.
"""

from __future__ import annotations

import torch.nn.functional as F
from torch import Tensor

from decoy_cli.damage.networks import DogOutput
from decoy_cli.modeling.train_options import DogLossWeights


def dog_loss(
    output: DogOutput, damage: Tensor, hit_group_index: Tensor, weights: DogLossWeights
) -> tuple[Tensor, dict[str, float]]:
    """Weighted sum of the damage MSE (HP / 100, `damage` (K, 1)), the hit-group cross-entropy
    (`hit_group_index` (K,) int64 in HIT_GROUPS order) and the KL divergence of the posterior
    from N(0, I) (summed over the latent, averaged over the batch); also each term as a float."""
    mse = F.mse_loss(output.damage, damage)
    cross_entropy = F.cross_entropy(output.hit_logits, hit_group_index)
    kl = (-0.5 * (1 + output.logvar - output.mu.pow(2) - output.logvar.exp()).sum(1)).mean()
    total = weights.damage * mse + weights.hit_group * cross_entropy + weights.kl * kl
    parts = {
        "total": float(total.detach()),
        "damage": float(mse.detach()),
        "hit_group": float(cross_entropy.detach()),
        "kl": float(kl.detach()),
    }
    return total, parts
