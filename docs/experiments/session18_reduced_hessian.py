import numpy as np, scipy.linalg as sl
def rdS(f):
    L=open(f).read().split('\n'); r,c,_=L[0].split(); M=np.zeros((int(r),int(c)))
    for l in L[1:]:
        if l: i,j,v=l.split(); M[int(i),int(j)]=float(v)
    return M
def rdT(f,n):
    M=np.zeros((n,n))
    for l in open(f):
        i,j,v=l.split(); i=int(i);j=int(j);v=float(v); M[i,j]+=v
        if i!=j: M[j,i]+=v
    return M
Jo=rdS('/tmp/d_Jo.txt'); A=rdS('/tmp/d_A.txt'); n=Jo.shape[1]
Ho=rdT('/tmp/d_Ho.txt',n); Hc=rdT('/tmp/d_Hc.txt',n)
print('n',n,'m',A.shape[0],'rank A',np.linalg.matrix_rank(A))
Z=sl.null_space(A); print('null dim',Z.shape[1])
G=Z.T@Jo.T@Jo@Z; So=Z.T@Ho@Z; Sc=Z.T@Hc@Z
W=G+So+Sc
for name,H in [('GN',G),('exact',W),('GN+obj',G+So)]:
    e=np.linalg.eigvalsh(H); print(name,'eig min %.3g max %.3g'%(e.min(),e.max()))
# rate of GN iteration: eigenvalues of I - G^-1 W
ev=np.linalg.eigvals(np.linalg.solve(G,W)); ev=np.real(ev)
print('G^-1 W eig range', ev.min(), ev.max(), 'rate', np.abs(1-ev).max())
ev=np.real(np.linalg.eigvals(np.linalg.solve(G+So,W))); print('(G+So)^-1 W', ev.min(),ev.max(), np.abs(1-ev).max())
print('norms G %.3g So %.3g Sc %.3g'%(np.linalg.norm(G,2),np.linalg.norm(So,2),np.linalg.norm(Sc,2)))
np.save('/tmp/Z.npy',Z)
e,V=np.linalg.eigh(W)
print('smallest eigs',e[:8])
for k in range(4):
    v=Z@V[:,k]
    idx=np.argsort(-np.abs(v))[:10]
    print(k, e[k], [(int(i),round(float(v[i]),3)) for i in idx])
print('count |eig|<1e-9:', (np.abs(e)<1e-9).sum(), ' <1e-6:', (np.abs(e)<1e-6).sum(), '<1e-4', (np.abs(e)<1e-4).sum())
eg,Vg=np.linalg.eigh(G)
keep=Vg[:, eg>1e-9]
G2=keep.T@G@keep; W2=keep.T@W@keep; S2=keep.T@(So+Sc)@keep
ev=np.real(np.linalg.eigvals(np.linalg.solve(G2,W2))); 
print('on range(G): G^-1 W eig', np.sort(ev)[:5], np.sort(ev)[-5:])
print('eig of W2', np.sort(np.linalg.eigvalsh(W2))[:5])
print('eig of G2', np.sort(np.linalg.eigvalsh(G2))[:10])
for name,S in [('obj',So),('con',Sc)]:
    M=keep.T@(G+S)@keep
    ev=np.sort(np.real(np.linalg.eigvals(np.linalg.solve(G2,M)))); print(name, ev[:3], ev[-3:])
# direction with largest ratio
ev,V=sl.eigh(W2,G2)
for k in [0,1,-1,-2]:
    v=Z@(keep@V[:,k]); v/=np.abs(v).max()
    idx=np.argsort(-np.abs(v))[:8]
    print('ratio %.3f'%ev[k], [(int(i),round(float(v[i]),2)) for i in idx])
