"""Offline training of the perception models (needs torch and a dataset; not used at run time).

``python -m training.train_detector`` trains the CNN pole detector whose weights
:mod:`perception.vision.cnn_detector` loads. Nothing in ``perception`` or ``spl_env`` imports
this package.
"""
