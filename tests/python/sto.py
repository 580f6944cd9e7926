"""A minimal reader of OpenSim storage (.sto) files as the C++ programs write them."""
import numpy as np


def read_sto(path):
    """{column label: numpy array} of a tab-separated .sto file."""
    lines = open(path).read().splitlines()
    start = lines.index("endheader") + 1
    labels = lines[start].split("\t")
    rows = np.array([[float(x) for x in line.split("\t")] for line in lines[start + 1:] if line.strip()])
    return {label: rows[:, k] for k, label in enumerate(labels)}
