"""A one-input MATLAB .fis probing how one membership function is read (not a test module)."""

from __future__ import annotations


def fis_with_input_mf(mf: str, input_range: str = "[-1 1]") -> str:
    """A one-input .fis whose input has a covering gaussian and the given MF as its term 2."""
    return f"""[System]
Name='probe'
Type='mamdani'
NumInputs=1
NumOutputs=1
NumRules=1
AndMethod='min'
OrMethod='max'
ImpMethod='min'
AggMethod='max'
DefuzzMethod='centroid'

[Input1]
Name='x'
Range={input_range}
NumMFs=2
MF1='all':'gaussmf',[1 0]
MF2='probe':{mf}

[Output1]
Name='y'
Range=[0 1]
NumMFs=1
MF1='a':'trimf',[0 0.5 1]

[Rules]
1 , 1 (1) : 1
"""
