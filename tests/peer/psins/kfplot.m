function kfplot(xkpk, res, varargin)
% calbench's harness: in place of PSINS's figures, the filter's last estimate and its sigma, one
% quantity per line (read by bench/drive/peer_psins.py). Columns of xkpk as PSINS's demo records
% them: 21 states, then their variances, then the time.
global glv
n = 21; x = xkpk(end, 1:n); p = sqrt(xkpk(end, n + (1:n)));
printf('t_end %.3f\n', xkpk(end, end));
printf('eb_deg_h %.4f %.4f %.4f\n', x(7:9) / glv.dph);
printf('eb_sigma_deg_h %.4f %.4f %.4f\n', p(7:9) / glv.dph);
printf('db_mg %.5f %.5f %.5f\n', x(10:12) / glv.mg);
printf('db_sigma_mg %.5f %.5f %.5f\n', p(10:12) / glv.mg);
printf('mu_deg %.5f %.5f %.5f\n', x(13:15) / glv.deg);
printf('mu_sigma_deg %.5f %.5f %.5f\n', p(13:15) / glv.deg);
if numel(varargin) >= 3
  printf('eb0_deg_h %.4f %.4f %.4f\n', varargin{1} / glv.dph);
  printf('db0_mg %.5f %.5f %.5f\n', varargin{2} / glv.mg);
  printf('mu0_deg %.5f %.5f %.5f\n', varargin{3} / glv.deg);
end
end
