"""The tooling that makes, scores and calibrates the damage models (`decoy train`, `decoy
models`): nothing here is loaded when a round is played (decoy_cli/damage/ holds what is).

* samples.py: training samples from ESTA rounds (with sample_set.py, damage_rows.py,
  frames_mode.py, events_mode.py, filled_views.py), split.py: the split by match or round;
* train_options.py, losses.py, training.py, training_run.py, provenance.py: training a model and
  writing it with where it came from;
* scores.py: the scores (ROC AUC, best F1, Wasserstein cells, floors); network_evaluation.py:
  DIP and DOG scored on samples; evaluation_figures.py: their figures; hp_lost.py: any damage
  outcome model scored on the HP lost; folder_evaluation.py: a `--models` choice scored on data
  files (`decoy models evaluate`);
* calibration_fit.py: how calibrated DIP is, and fitting its recalibration;
  folder_calibration.py: a model folder calibrated on data files (`decoy models calibrate`);
  fight_threshold.py: the DIP threshold the fight decides by (`decoy models fight-threshold`);
* rules_fit.py: the learned parts of the rules-grounded model (`decoy models fit-rules`);
* paper_import.py, paper_download.py: the paper's published checkpoints, imported and
  downloaded (`decoy models import-decoy`, `download-decoy`).
"""
