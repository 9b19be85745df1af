"""The paper's benchmark: campaigns (local or Ray), metrics, Table 1, the ablation and the report."""
