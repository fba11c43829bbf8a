"""Attention layers, blocks and the sine positional encoding of the reference network.

Tensors are batch-first (N, L, C) here; the reference is sequence-first (L, N, C), which
is the same computation. Parameter names match the reference state dict.
"""

from __future__ import annotations

import math

import torch
import torch.nn.functional as F
from torch import nn


def sine_position_encoding(height: int, width: int, channels: int) -> torch.Tensor:
    """DETR's normalised sine encoding of an all-ones mask, as (1, H*W, channels).

    Computed with the reference's float32 operations in the same order, so the
    precomputed constant is bit-identical to what the reference builds at run time.
    """
    num_feats = channels // 2
    ones = torch.ones(1, height, width)
    y_embed = ones.cumsum(1, dtype=torch.float32)
    x_embed = ones.cumsum(2, dtype=torch.float32)
    eps, scale = 1e-6, 2 * math.pi
    y_embed = y_embed / (y_embed[:, -1:, :] + eps) * scale
    x_embed = x_embed / (x_embed[:, :, -1:] + eps) * scale
    dim_t = torch.arange(num_feats, dtype=torch.float32)
    dim_t = 10000 ** (2 * (dim_t // 2) / num_feats)
    pos_x = x_embed[:, :, :, None] / dim_t
    pos_y = y_embed[:, :, :, None] / dim_t
    pos_x = torch.stack((pos_x[..., 0::2].sin(), pos_x[..., 1::2].cos()), dim=4).flatten(3)
    pos_y = torch.stack((pos_y[..., 0::2].sin(), pos_y[..., 1::2].cos()), dim=4).flatten(3)
    pos = torch.cat((pos_y, pos_x), dim=3)  # (1, H, W, C): y features first
    return pos.reshape(1, height * width, channels)


class MultiheadAttention(nn.Module):
    """`nn.MultiheadAttention`'s parameters and arithmetic, written with plain ops.

    Plain linear + scaled_dot_product_attention keeps every tensor at most 4-D and
    exports to ONNX/TFLite without the fused op.
    """

    def __init__(self, dim: int, num_heads: int) -> None:
        super().__init__()
        self.num_heads = num_heads
        self.in_proj_weight = nn.Parameter(torch.empty(3 * dim, dim))
        self.in_proj_bias = nn.Parameter(torch.zeros(3 * dim))
        self.out_proj = nn.Linear(dim, dim)
        nn.init.xavier_uniform_(self.in_proj_weight)
        nn.init.zeros_(self.out_proj.bias)

    def _heads(self, x: torch.Tensor) -> torch.Tensor:
        n, length, dim = x.shape
        return x.reshape(n, length, self.num_heads, dim // self.num_heads).transpose(1, 2)

    def forward(self, query: torch.Tensor, key: torch.Tensor, value: torch.Tensor) -> torch.Tensor:
        w_q, w_k, w_v = self.in_proj_weight.chunk(3)
        b_q, b_k, b_v = self.in_proj_bias.chunk(3)
        q = self._heads(F.linear(query, w_q, b_q))
        k = self._heads(F.linear(key, w_k, b_k))
        v = self._heads(F.linear(value, w_v, b_v))
        out = F.scaled_dot_product_attention(q, k, v)  # (N, heads, L, head_dim)
        n, _, length, _ = out.shape
        return self.out_proj(out.transpose(1, 2).reshape(n, length, -1))


class AttentionLayer(nn.Module):
    """Post-norm layer: self-attention, cross-attention to `memory`, feed-forward."""

    def __init__(self, dim: int, num_heads: int, ffn_dim: int) -> None:
        super().__init__()
        self.self_attn = MultiheadAttention(dim, num_heads)
        # The reference keeps a second cross-attention and norm that it never uses; we
        # keep only the used one, under the same names, so checkpoints load as they are.
        self.multihead_attn_list = nn.ModuleList([MultiheadAttention(dim, num_heads)])
        self.norm2_list = nn.ModuleList([nn.LayerNorm(dim)])
        self.linear1 = nn.Linear(dim, ffn_dim)
        self.linear2 = nn.Linear(ffn_dim, dim)
        self.norm1 = nn.LayerNorm(dim)
        self.norm3 = nn.LayerNorm(dim)

    def forward(
        self, tgt: torch.Tensor, memory: torch.Tensor, pos: torch.Tensor, memory_pos: torch.Tensor
    ) -> torch.Tensor:
        q = tgt + pos
        tgt = self.norm1(tgt + self.self_attn(q, q, tgt))
        cross = self.multihead_attn_list[0](tgt + pos, memory + memory_pos, memory)
        tgt = self.norm2_list[0](tgt + cross)
        tgt = self.norm3(tgt + self.linear2(F.relu(self.linear1(tgt))))
        return tgt


class AttentionBlock(nn.Module):
    """A stack of attention layers on one grid, with that grid's positional encoding."""

    def __init__(self, dim: int, num_heads: int, ffn_dim: int, num_layers: int, grid: int) -> None:
        super().__init__()
        self.layers = nn.ModuleList(
            [AttentionLayer(dim, num_heads, ffn_dim) for _ in range(num_layers)]
        )
        self.grid = grid
        # A constant of the grid size: precomputed, and not part of the state dict.
        self.register_buffer("pos", sine_position_encoding(grid, grid, dim), persistent=False)

    def encode(self, tokens: torch.Tensor) -> torch.Tensor:
        """Encoder use: every layer cross-attends to its own input."""
        for layer in self.layers:
            tokens = layer(tokens, tokens, self.pos, self.pos)
        return tokens

    def decode(self, features: torch.Tensor, query: torch.Tensor) -> torch.Tensor:
        """Decoder use: the query cross-attends to the features of the same grid."""
        for layer in self.layers:
            query = layer(query, features, self.pos, self.pos)
        return query
